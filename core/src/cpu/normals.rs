//! `tri_normals` — per triangle: the area-weighted face normal `(b - a) × (c - a)`.
//! `vertex_normals` — per particle: the sum of the adjacent face normals, normalised, and
//! the wind force, which stays in the force buffer for the next substep's `forces`.

use super::{Exec, for_each, for_each2, v3, v4};
use crate::grid::{FACE_SLOTS, StepParams, V4};

/// Face normals `N` with `|N| = 2 · area(t)`; w holds `|N|`.
pub fn tri_normals(exec: Exec, triangles: &[[u32; 3]], pos: &[V4], face: &mut [V4]) {
    for_each(exec, face, |t, f| {
        let [a, b, c] = triangles[t];
        let (xa, xb, xc) = (v3(pos[a as usize]), v3(pos[b as usize]), v3(pos[c as usize]));
        let nrm = (xb - xa).cross(xc - xa);
        *f = v4(nrm, nrm.length());
    });
}

/// Vertex normals and wind. A face of normal `N` (|N| = 2A) under wind `w` with
/// coefficient `c` feels `c · A · (n̂·w) n̂ = c (N·w) N / (2 |N|)`; each corner takes a third.
pub fn vertex_normals(
    exec: Exec,
    p: &StepParams,
    face_slots: &[[i32; FACE_SLOTS]],
    face: &[V4],
    normal: &mut [V4],
    force: &mut [V4],
) {
    let w = v3(p.wind);
    let c = p.wind[3] / 6.0;
    for_each2(exec, normal, force, |i, nrm, f| {
        let mut sum = glam::Vec3::ZERO;
        let mut wind = glam::Vec3::ZERO;
        for &t in &face_slots[i] {
            if t < 0 {
                continue;
            }
            let f4 = face[t as usize];
            let nf = v3(f4);
            sum += nf;
            if f4[3] > 0.0 {
                wind += nf * (c * nf.dot(w) / f4[3]);
            }
        }
        *nrm = v4(sum.normalize_or_zero(), 0.0);
        *f = v4(wind, 0.0);
    });
}
