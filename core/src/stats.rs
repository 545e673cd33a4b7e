//! Summaries of a state (the CLI's report and the tests' checks) and its file formats.

use std::io::Write;

use serde::{Deserialize, Serialize};

use crate::grid::{ClothState, ClothTopology, SpringKind};

/// Statistics of the state at the end of one substep.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct SubstepStats {
    /// Largest structural strain `|L| / rest - 1`, 0 when nothing is stretched.
    pub max_strain: f32,
    /// Kinetic energy `Σ ½ m |v|²`, J.
    pub kinetic_energy: f32,
}

/// What `clothlab sim` reports about a state.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StateSummary {
    /// Largest structural strain `|L| / rest - 1` (0 when nothing is stretched).
    pub max_strain: f32,
    /// Lowest particle height, m.
    pub lowest_y: f32,
    /// Number of non-finite components in positions, velocities and normals.
    pub nan_count: usize,
}

/// Largest strain over the springs of `kind`.
pub fn max_strain(state: &ClothState, topo: &ClothTopology, kind: SpringKind) -> f32 {
    topo.springs
        .iter()
        .filter(|s| s.kind == kind as u32)
        .map(|s| {
            let a = state.pos[s.a as usize];
            let b = state.pos[s.b as usize];
            let len = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            len / s.rest - 1.0
        })
        .fold(0.0f32, f32::max)
}

/// The summary of `state`.
pub fn summarize(state: &ClothState, topo: &ClothTopology) -> StateSummary {
    let nan_count = [&state.pos, &state.vel, &state.normal]
        .iter()
        .flat_map(|v| v.iter().flat_map(|p| p[..3].iter()))
        .filter(|x| !x.is_finite())
        .count();
    let lowest_y = state.pos.iter().map(|p| p[1]).fold(f32::INFINITY, f32::min);
    StateSummary { max_strain: max_strain(state, topo, SpringKind::Structural), lowest_y, nan_count }
}

/// Writes the cloth as a Wavefront OBJ mesh: `v x y z` per particle (index `j·n + i + 1`),
/// `vt u v`, `vn x y z`, and `f a/a/a b/b/b c/c/c` per triangle (in a scene of several
/// cloths, each cloth's faces an object, `o cloth[k]`). Any 3-D tool opens it.
pub fn write_obj(w: &mut impl Write, state: &ClothState, topo: &ClothTopology) -> std::io::Result<()> {
    match state.n {
        0 => writeln!(w, "# clothlab cloth state, a mesh of {} particles", state.pos.len())?,
        n => writeln!(w, "# clothlab cloth state, {n}x{n} particles")?,
    }
    for p in &state.pos {
        writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
    }
    for t in &topo.uv {
        writeln!(w, "vt {} {}", t[0], t[1])?;
    }
    for q in &state.normal {
        writeln!(w, "vn {} {} {}", q[0], q[1], q[2])?;
    }
    // A scene of several cloths: an object (`o cloth[k]`) each, its faces.
    let parts: Vec<std::ops::Range<usize>> = match topo.parts() {
        [] => std::iter::once(0..topo.triangles.len()).collect(),
        parts => parts.iter().map(|p| p.triangle_range()).collect(),
    };
    for (k, tris) in parts.into_iter().enumerate() {
        if !topo.parts().is_empty() {
            writeln!(w, "o cloth[{k}]")?;
        }
        for [a, b, c] in &topo.triangles[tris] {
            let (a, b, c) = (a + 1, b + 1, c + 1);
            writeln!(w, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}")?;
        }
    }
    Ok(())
}

/// Writes the full state as JSON: `{"n": n, "pos": [[x,y,z,w],…], "vel": …, "force": …,
/// "normal": …}`, particle `(i, j)` at index `j·n + i`; `pos[k][3]` is 1 for a free particle,
/// 0 for a pinned one. [`ClothState`]'s serde form, so it loads back with serde_json.
pub fn write_json(w: &mut impl Write, state: &ClothState) -> std::io::Result<()> {
    serde_json::to_writer(&mut *w, state).map_err(std::io::Error::other)?;
    writeln!(w)
}
