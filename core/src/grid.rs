//! The grid builder: particles, triangles and springs.
//!
//! Particle `(i, j)` (column `i`, row `j`, both `0 … n-1`) has index `j·n + i`. Row 0 is
//! the top edge, the one pinned. Every per-particle buffer is a `Vec<[f32; 4]>` (structure
//! of arrays, 16-byte elements, the layout the GPU buffers have).

use bytemuck::{Pod, Zeroable};
use serde::{Deserialize, Serialize};

use crate::params::{ParamError, SimParams};
use crate::scene::{Pinning, Scene};

/// A 16-byte particle attribute: xyz plus one spare or flag component.
pub type V4 = [f32; 4];

pub use crate::tables::{Colours, FACE_SLOTS, Rows, SLOTS, STRAIN_SLOTS, TETHER_SLOTS};

/// The three spring families.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[repr(u32)]
pub enum SpringKind {
    /// i±1 or j±1.
    Structural = 0,
    /// The diagonals of a quad.
    Shear = 1,
    /// i±2 or j±2.
    Bend = 2,
}

/// Grid offsets `(di, dj)` of the 12 slots, in the fixed order every gather uses:
/// structural left, right, up, down; shear up-left, up-right, down-left, down-right;
/// bend left, right, up, down.
pub const SLOT_OFFSETS: [(i32, i32); SLOTS] =
    [(-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (1, -1), (-1, 1), (1, 1), (-2, 0), (2, 0), (0, -2), (0, 2)];

/// The family of slot `s`.
pub fn slot_kind(s: usize) -> SpringKind {
    match s {
        0..=3 => SpringKind::Structural,
        4..=7 => SpringKind::Shear,
        _ => SpringKind::Bend,
    }
}

/// A long-range attachment (Kim, Chentanez & Müller 2012): the particle may be at most
/// `(1 + τ) · rest` from the pinned particle `pin` (`#[repr(C)]`, mirrored in the shaders).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable, Serialize, Deserialize)]
pub struct Tether {
    /// Index of the pinned particle, or -1 for an empty slot.
    pub pin: i32,
    /// Distance to the pin in the flat rest sheet (the geodesic distance), m.
    pub rest: f32,
}

impl Tether {
    /// An empty slot.
    pub const EMPTY: Self = Self { pin: -1, rest: 0.0 };
}

/// The spring constants of the regular grid (see [`ClothTopology::grid_slots`]), for GPU
/// kernels to read from a uniform block (the thesis's constant memory) instead of the
/// per-particle table. `#[repr(C)]`, mirrored in the shaders; `neighbor` is unused (the offsets are [`SLOT_OFFSETS`]).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct GridSpringConstants {
    /// Rest length and constants of slot `s` for every particle that has that slot
    /// ([`ClothTopology::grid_slots`]).
    pub slots: [SpringSlot; SLOTS],
    /// 1 when `slots` is valid (the table is the grid's, so kernels compute neighbours
    /// from offsets everywhere), 0 when kernels must read the table.
    pub enabled: u32,
    /// Padding to 16 bytes (three scalars: a WGSL uniform array needs a 16-byte stride,
    /// and a `vec3` pad would be aligned to 16).
    pub _pad0: u32,
    /// Padding.
    pub _pad1: u32,
    /// Padding.
    pub _pad2: u32,
}

impl GridSpringConstants {
    /// From the topology's uniform interior slots, if it has them.
    pub fn new(topo: &ClothTopology) -> Self {
        match topo.grid_slots() {
            Some(slots) => Self { slots, enabled: 1, _pad0: 0, _pad1: 0, _pad2: 0 },
            None => Self { slots: [SpringSlot::EMPTY; SLOTS], enabled: 0, _pad0: 0, _pad1: 0, _pad2: 0 },
        }
    }
}

/// One slot of the per-particle gather table (`#[repr(C)]`, mirrored in the shaders).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable, Serialize, Deserialize)]
pub struct SpringSlot {
    /// Index of the particle at the other end; -1 for an empty slot; `-2 - other` for a
    /// spring the strain limit does not hold although its slot is below
    /// [`STRAIN_SLOTS`] (a mesh's bending spring at a vertex with fewer than
    /// `STRAIN_SLOTS` edges: the table packs its springs, edges first). See
    /// [`SpringSlot::other`].
    pub neighbor: i32,
    /// Rest length, m.
    pub rest: f32,
    /// Stiffness, N/m.
    pub ks: f32,
    /// Damping, N·s/m.
    pub kd: f32,
}

impl SpringSlot {
    /// An empty slot.
    pub const EMPTY: Self = Self { neighbor: -1, rest: 0.0, ks: 0.0, kd: 0.0 };

    /// The particle at the other end, if the slot holds a spring (strain-limited or not).
    #[inline(always)]
    pub fn other(&self) -> Option<usize> {
        match self.neighbor {
            -1 => None,
            k if k >= 0 => Some(k as usize),
            k => Some((-2 - k) as usize),
        }
    }

    /// `neighbor` for a spring to `other` that the strain limit skips.
    pub fn unlimited(other: u32) -> i32 {
        -2 - other as i32
    }
}

/// One spring of the flat list the scatter (naive) kernels walk (`#[repr(C)]`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable, Serialize, Deserialize)]
pub struct Spring {
    /// First particle.
    pub a: u32,
    /// Second particle.
    pub b: u32,
    /// Rest length, m.
    pub rest: f32,
    /// Stiffness, N/m.
    pub ks: f32,
    /// Damping, N·s/m.
    pub kd: f32,
    /// [`SpringKind`] as u32.
    pub kind: u32,
}

/// The mutable state of the cloth: what a solver advances and a renderer draws.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ClothState {
    /// Particles per side; 0 for a mesh.
    pub n: u32,
    /// Positions, m; w = relative inverse mass: the reference mass
    /// ([`crate::step_params::StepParams::particle_mass`]) over the particle's (1 on a grid; a mesh's vertices
    /// carry their share of the area), 0 pinned.
    pub pos: Vec<V4>,
    /// Velocities, m/s; w unused (0).
    pub vel: Vec<V4>,
    /// Force accumulator, N. Between substeps it holds the wind force computed by the
    /// last `vertex_normals`; `forces` adds gravity and drag to it, `springs` the springs.
    pub force: Vec<V4>,
    /// Unit vertex normals; w unused.
    pub normal: Vec<V4>,
}

impl ClothState {
    /// Checks that this is a finite state of the cloth `topo` describes, an `n × n` grid
    /// or a mesh (what `Solver::set_state` accepts).
    pub fn check(&self, topo: &ClothTopology) -> Result<(), crate::error::SolverError> {
        let (n, np) = (topo.n, topo.num_particles());
        let bufs = [&self.pos, &self.vel, &self.force, &self.normal];
        if self.n != n || bufs.iter().any(|v| v.len() != np) {
            return Err(if topo.mesh.is_some() || self.n == 0 {
                crate::error::SolverError::Invalid(format!(
                    "the state has {} particles, the solver's cloth {np}",
                    self.pos.len()
                ))
            } else {
                crate::error::SolverError::GridMismatch { want: n, got: self.n }
            });
        }
        if !bufs.iter().all(|v| v.iter().flatten().all(|x| x.is_finite())) {
            return Err(crate::error::SolverError::Invalid("state holds non-finite values".into()));
        }
        Ok(())
    }
}

/// What does not change while simulating: connectivity and spring constants.
#[derive(Debug, Clone, PartialEq)]
pub struct ClothTopology {
    /// Particles per side; 0 for a mesh.
    pub n: u32,
    /// Texture coordinates per particle, in [0, 1]².
    pub uv: Vec<[f32; 2]>,
    /// Triangles, counter-clockwise seen from +y when the cloth lies flat.
    pub triangles: Vec<[u32; 3]>,
    /// The gather table, a row per particle: a grid's `SLOTS` slots (empty ones where a
    /// neighbour is missing), a mesh's springs of any number (compressed rows: its edges,
    /// the row's head, then its bending springs).
    pub slots: Rows<SpringSlot>,
    /// Every spring once, for scatter kernels.
    pub springs: Vec<Spring>,
    /// Per particle, its adjacent triangles: a grid's up-to-six (or -1) in a fixed order
    /// (`FACE_SLOTS` a row), a mesh's in triangle order (compressed rows, any number).
    pub face_slots: Rows<i32>,
    /// Per particle, the tethers to the nearest pins.
    pub tethers: Vec<[Tether; TETHER_SLOTS]>,
    /// Distance between neighbouring particles at rest, m (a mesh: the mean edge length).
    pub spacing: f32,
    /// What only a mesh has; `None` for a grid.
    pub mesh: Option<std::sync::Arc<MeshTables>>,
    /// Vertex Block Descent's colouring (`cpu::vbd::colouring`: a grid's 9 classes, a
    /// mesh's greedy colours), computed with the table.
    pub colours: std::sync::Arc<Colours>,
    /// The pins the scene's `[[pins]]` groups move (`crate::pins`; empty: none move).
    pub pins: crate::pins::MovingPins,
    /// The triangles' edges, each once (`crate::tables::edges`): found when first
    /// asked for (the contact between triangles), not at build.
    pub edges: std::sync::OnceLock<std::sync::Arc<Vec<[u32; 2]>>>,
}

/// The tables of a cloth made from a mesh that a grid computes from its place: the kind of
/// each spring slot and each particle's mass (for the spring constants).
#[derive(Debug, Clone, PartialEq)]
pub struct MeshTables {
    /// [`SpringKind`] of each entry of the gather table (as [`Rows::entries`]): edges are
    /// structural, the springs across an edge bending.
    pub slot_kind: Vec<SpringKind>,
    /// Each particle's mass, kg (its share of the cloth's area).
    pub mass: Vec<f32>,
    /// The lightest free particle's mass, kg (what the integrators' stability needs).
    pub min_mass: f32,
    /// XPBD's passes: pass `k` is springs `xpbd_passes[k] .. xpbd_passes[k + 1]` of the
    /// spring list, which the build sorts by pass (see `cloth::build_mesh`): a greedy
    /// colouring in which no two springs of a pass share a particle, the bending springs'
    /// passes first and the edges' last.
    pub xpbd_passes: Vec<u32>,
    /// The smallest rest distance between two particles that share no spring but a
    /// neighbour, m: self-collision's thickness must stay below half of it.
    pub closest_unsprung: f32,
    /// The smallest rest distance between a vertex and a triangle or two edges that share
    /// no vertex, m (at most two mean edges: pairs farther apart are not looked for): the
    /// contact between triangles' thickness must stay below [`TRIANGLE_THICKNESS_FRACTION`]
    /// of it. Measured when the mesh is built with `self_collision = "triangles"` (None
    /// otherwise: the search is not paid for by the other modes).
    ///
    /// [`TRIANGLE_THICKNESS_FRACTION`]: crate::params::TRIANGLE_THICKNESS_FRACTION
    pub closest_primitives: Option<f32>,
    /// The cloths of a scene of several, their ranges of the particles and triangles
    /// (empty for one cloth).
    pub parts: Vec<crate::mesh::ClothPart>,
}

impl ClothTopology {
    /// The triangles' edges, each once, in `crate::tables::edges`' order.
    pub fn edges(&self) -> &[[u32; 2]] {
        self.edges.get_or_init(|| std::sync::Arc::new(crate::tables::edges(&self.triangles)))
    }

    /// Number of particles.
    pub fn num_particles(&self) -> usize {
        self.uv.len()
    }

    /// The cloths of a scene of several (empty for one).
    pub fn parts(&self) -> &[crate::mesh::ClothPart] {
        self.mesh.as_ref().map_or(&[], |m| m.parts.as_slice())
    }

    /// The texture coordinates the renderers draw with: [`Self::uv`], cloth `k` of several
    /// moved by `RENDER_UV_STEP · k` along u. The fabric repeats, so it looks the same;
    /// `render.wgsl` reads the cloth's index back (`round(u / RENDER_UV_STEP)`) and tints
    /// each cloth of a scene of several its own colour. (Texture coordinates within
    /// ±`RENDER_UV_STEP / 2` of their cloth's are read back right.)
    pub fn render_uvs(&self) -> Vec<[f32; 2]> {
        let mut uv = self.uv.clone();
        for (k, part) in self.parts().iter().enumerate() {
            for t in &mut uv[part.range()] {
                t[0] += RENDER_UV_STEP * k as f32;
            }
        }
        uv
    }

    /// The 12 slots every particle at least two away from the border has, if all such
    /// particles' slots agree in rest length and constants (true for every grid that
    /// [`build_grid`] makes). Solvers then read them once instead of per particle.
    pub fn uniform_interior_slots(&self) -> Option<[SpringSlot; SLOTS]> {
        let n = self.n as usize;
        if n <= 4 || self.mesh.is_some() {
            return None;
        }
        let first = 2 * n + 2;
        let mut uni = [SpringSlot::EMPTY; SLOTS];
        uni.copy_from_slice(self.slots.row(first));
        for u in &mut uni {
            u.neighbor = 0;
        }
        for j in 2..n - 2 {
            for i in 2..n - 2 {
                let p = j * n + i;
                for (s, u) in uni.iter().enumerate() {
                    let t = &self.slots.row(p)[s];
                    let off = SLOT_OFFSETS[s].0 as isize + SLOT_OFFSETS[s].1 as isize * n as isize;
                    if t.neighbor as isize != p as isize + off || t.rest != u.rest || t.ks != u.ks || t.kd != u.kd {
                        return None;
                    }
                }
            }
        }
        Some(uni)
    }

    /// The 12 slots of the regular grid, if the whole table is one: slot `s` of every
    /// particle is filled exactly when the neighbour at [`SLOT_OFFSETS`]`[s]` exists, points
    /// at it, and has these rest length and constants (true for every grid that [`build_grid`]
    /// makes). GPU kernels then compute neighbours and read constants from a uniform block
    /// everywhere, border included, and never read the table. A slot no particle has
    /// (n ≤ 2) is [`SpringSlot::EMPTY`].
    pub fn grid_slots(&self) -> Option<[SpringSlot; SLOTS]> {
        if self.mesh.is_some() || self.n == 0 {
            return None;
        }
        let n = self.n as i64;
        let mut uni = [None::<SpringSlot>; SLOTS];
        for j in 0..n {
            for i in 0..n {
                let p = (j * n + i) as usize;
                for (s, u) in uni.iter_mut().enumerate() {
                    let t = self.slots.row(p)[s];
                    let (ni, nj) = (i + SLOT_OFFSETS[s].0 as i64, j + SLOT_OFFSETS[s].1 as i64);
                    if ni < 0 || nj < 0 || ni >= n || nj >= n {
                        if t.neighbor >= 0 {
                            return None;
                        }
                        continue;
                    }
                    if t.neighbor as i64 != nj * n + ni {
                        return None;
                    }
                    let t = SpringSlot { neighbor: 0, ..t };
                    match u {
                        None => *u = Some(t),
                        Some(u) if *u != t => return None,
                        Some(_) => {}
                    }
                }
            }
        }
        Some(uni.map(|u| u.unwrap_or(SpringSlot::EMPTY)))
    }

    /// Whether `params` can simulate this cloth ([`SimParams::validate_for`]; a mesh is
    /// checked at its lightest particle's mass).
    pub fn validate_params(&self, params: &SimParams) -> Result<(), ParamError> {
        match &self.mesh {
            None => params.validate_for(self.n, self.spacing),
            Some(m) => {
                params.check_mesh(self.num_particles(), m.closest_unsprung)?;
                if params.self_collision.triangles() {
                    let Some(closest) = m.closest_primitives else {
                        return Err(ParamError::new(
                            "self_collision",
                            "triangles",
                            "this mesh was built without the contact between triangles, whose thickness bound is measured \
                             when the mesh is built: load the scene with self_collision = \"triangles\"",
                        ));
                    };
                    params.check_triangles(closest, "this mesh's")?;
                }
                params.validate_for_mass(m.min_mass, self.spacing, "for this mesh")
            }
        }
    }

    /// Rebuilds the spring constants for new parameters (rest lengths stay).
    pub fn set_spring_constants(&mut self, params: &SimParams) {
        if let Some(mesh) = self.mesh.clone() {
            let consts = |a: usize, b: usize, kind: SpringKind| {
                params.spring_constants_for_mass(mesh.mass[a].min(mesh.mass[b]), self.spacing)[kind as usize]
            };
            for a in 0..self.slots.rows() {
                let first = self.slots.range(a).start;
                for (s, slot) in self.slots.row_mut(a).iter_mut().enumerate() {
                    if let Some(b) = slot.other() {
                        (slot.ks, slot.kd) = consts(a, b, mesh.slot_kind[first + s]);
                    }
                }
            }
            for s in &mut self.springs {
                let kind = if s.kind == SpringKind::Bend as u32 { SpringKind::Bend } else { SpringKind::Structural };
                (s.ks, s.kd) = consts(s.a as usize, s.b as usize, kind);
            }
            return;
        }
        let consts = params.spring_constants(self.n, self.spacing);
        for (k, slot) in self.slots.entries_mut().iter_mut().enumerate() {
            if slot.neighbor >= 0 {
                let (ks, kd) = consts[slot_kind(k % SLOTS) as usize];
                slot.ks = ks;
                slot.kd = kd;
            }
        }
        for s in &mut self.springs {
            let (ks, kd) = consts[s.kind as usize];
            s.ks = ks;
            s.kd = kd;
        }
    }
}

/// (ks, kd) per [`SpringKind`] for `topo`'s cloth: what the spring tables hold, so a
/// parameter change that leaves these equal (wind, gravity, …) needs no table upload.
pub fn spring_constants(params: &SimParams, topo: &ClothTopology) -> [(f32, f32); 3] {
    params.spring_constants(topo.n, topo.spacing)
}

/// Index of triangle `t` (0 or 1) of quad `(qi, qj)`; quads are `(n-1) × (n-1)`.
fn tri_index(n: u32, qi: u32, qj: u32, t: u32) -> i32 {
    (2 * (qj * (n - 1) + qi) + t) as i32
}

/// Builds the initial state and the topology for a validated scene and parameters.
pub fn build_grid(scene: &Scene, params: &SimParams) -> Result<(ClothState, ClothTopology), ParamError> {
    scene.validate()?;
    params.validate()?;
    let n = scene.cloth.n;
    let nu = n as usize;
    let np = nu * nu;
    let spacing = scene.cloth.size / (n - 1) as f32;

    let mut pos = Vec::with_capacity(np);
    let mut uv = Vec::with_capacity(np);
    for j in 0..n {
        for i in 0..n {
            let pinned = scene.cloth.pinning.holds(n, i, j);
            let [x, y, z] = scene.cloth.rest_position(i, j);
            pos.push([x, y, z, if pinned { 0.0 } else { 1.0 }]);
            uv.push([i as f32 / (n - 1) as f32, j as f32 / (n - 1) as f32]);
        }
    }
    // The `[[pins]]` groups hold the particles in their boxes too.
    let group_of = crate::pins::select(&scene.pins, &pos)?;
    for (p, g) in pos.iter_mut().zip(&group_of) {
        if g.is_some() {
            p[3] = 0.0;
        }
    }
    let moving_pins = crate::pins::moving(&scene.pins, &group_of, &pos);

    // Triangles: quad (qi, qj) with corners p00 = (qi, qj), p10, p01, p11, split along the
    // p00–p11 diagonal. t0 = (p00, p01, p11), t1 = (p00, p11, p10): counter-clockwise seen
    // from +y for the initial sheet (x right, z towards the viewer), so normals start at +y.
    let mut triangles = Vec::with_capacity(2 * (nu - 1) * (nu - 1));
    for qj in 0..n - 1 {
        for qi in 0..n - 1 {
            let p00 = qj * n + qi;
            let p10 = p00 + 1;
            let p01 = p00 + n;
            let p11 = p01 + 1;
            triangles.push([p00, p01, p11]);
            triangles.push([p00, p11, p10]);
        }
    }

    // Face slots, fixed order: quad (i-1, j-1) t0, t1; quad (i, j-1) t0 (it holds p01 = (i, j)
    // ... see below); quad (i-1, j) t1; quad (i, j) t0, t1.
    // Vertex (i, j) is p11 of quad (i-1, j-1): in t0 and t1; p01 of quad (i, j-1): in t0;
    // p10 of quad (i-1, j): in t1; p00 of quad (i, j): in t0 and t1.
    let mut face_slots = Vec::with_capacity(np);
    for j in 0..n {
        for i in 0..n {
            let mut f = [-1i32; FACE_SLOTS];
            let has_l = i > 0;
            let has_r = i < n - 1;
            let has_u = j > 0;
            let has_d = j < n - 1;
            if has_l && has_u {
                f[0] = tri_index(n, i - 1, j - 1, 0);
                f[1] = tri_index(n, i - 1, j - 1, 1);
            }
            if has_r && has_u {
                f[2] = tri_index(n, i, j - 1, 0);
            }
            if has_l && has_d {
                f[3] = tri_index(n, i - 1, j, 1);
            }
            if has_r && has_d {
                f[4] = tri_index(n, i, j, 0);
                f[5] = tri_index(n, i, j, 1);
            }
            face_slots.push(f);
        }
    }

    params.validate_for(n, spacing)?;
    let consts = params.spring_constants(n, spacing);
    let mut slots = Vec::with_capacity(np * SLOTS);
    let mut springs = Vec::new();
    for j in 0..n as i32 {
        for i in 0..n as i32 {
            let me = (j * n as i32 + i) as u32;
            for (s, &(di, dj)) in SLOT_OFFSETS.iter().enumerate() {
                let (ni, nj) = (i + di, j + dj);
                if ni < 0 || nj < 0 || ni >= n as i32 || nj >= n as i32 {
                    slots.push(SpringSlot::EMPTY);
                    continue;
                }
                let other = (nj * n as i32 + ni) as u32;
                let kind = slot_kind(s);
                let (ks, kd) = consts[kind as usize];
                let rest = spacing * ((di * di + dj * dj) as f32).sqrt();
                slots.push(SpringSlot { neighbor: other as i32, rest, ks, kd });
                if me < other {
                    springs.push(Spring { a: me, b: other, rest, ks, kd, kind: kind as u32 });
                }
            }
        }
    }

    // Tethers: to both corners for TopCorners, to the pin straight above for TopEdge, to
    // the two nearest (in the flat sheet) for a list of points. A list is searched by brute
    // force, so a very long list on a very large grid (over 2.5e8 pairs) gets no tethers.
    // With `[[pins]]` groups, every held particle is a listed pin.
    let held = pos.iter().filter(|p| p[3] == 0.0).count();
    let listed: Vec<u32> = match &scene.cloth.pinning {
        _ if !scene.pins.is_empty() && held * np <= 250_000_000 => {
            (0..np as u32).filter(|&k| pos[k as usize][3] == 0.0).collect()
        }
        _ if !scene.pins.is_empty() => Vec::new(),
        Pinning::Points(p) if p.len() * np <= 250_000_000 => {
            let mut v: Vec<u32> = p.iter().map(|q| q[1] * n + q[0]).collect();
            v.sort_unstable();
            v.dedup();
            v
        }
        _ => Vec::new(),
    };
    let dist = |a: V4, b: V4| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
    let mut tethers = Vec::with_capacity(np);
    // The (up to) two pins of `listed` nearest particle `me` in the flat sheet.
    let nearest_two = |listed: &[u32], me: usize, nearest: &mut [(f32, u32); TETHER_SLOTS]| -> Vec<u32> {
        for &pin in listed {
            let d = (dist(pos[me], pos[pin as usize]), pin);
            if d < nearest[1] {
                nearest[1] = d;
                if nearest[1] < nearest[0] {
                    nearest.swap(0, 1);
                }
            }
        }
        [nearest[0].1, nearest[1].1][..listed.len().min(TETHER_SLOTS)].to_vec()
    };
    for j in 0..n {
        for i in 0..n {
            let me = (j * n + i) as usize;
            let mut t = [Tether::EMPTY; TETHER_SLOTS];
            let mut nearest = [(f32::INFINITY, 0u32); TETHER_SLOTS];
            let pins: Vec<u32> = match scene.cloth.pinning {
                _ if !scene.pins.is_empty() => nearest_two(&listed, me, &mut nearest),
                Pinning::TopCorners => vec![0, n - 1],
                Pinning::TopEdge => vec![i],
                // A mesh's rules (refused for a grid by `Scene::validate`).
                Pinning::None | Pinning::Vertices(_) | Pinning::BelowY(_) | Pinning::AboveY(_) => Vec::new(),
                Pinning::Points(_) => nearest_two(&listed, me, &mut nearest),
            };
            if pos[me][3] != 0.0 {
                for (slot, &pin) in t.iter_mut().zip(&pins) {
                    *slot = Tether { pin: pin as i32, rest: dist(pos[me], pos[pin as usize]) };
                }
            }
            tethers.push(t);
        }
    }

    let zero = vec![[0.0f32; 4]; np];
    let v0 = scene.cloth.velocity;
    let vel = pos.iter().map(|x| if x[3] == 0.0 { [0.0; 4] } else { [v0[0], v0[1], v0[2], 0.0] }).collect();
    let state = ClothState { n, vel, pos, force: zero.clone(), normal: zero };
    let slots = Rows::fixed(slots, SLOTS, STRAIN_SLOTS);
    let face_slots = Rows::fixed(face_slots.concat(), FACE_SLOTS, FACE_SLOTS);
    let mut topo = ClothTopology {
        n,
        uv,
        triangles,
        slots,
        springs,
        face_slots,
        tethers,
        spacing,
        mesh: None,
        colours: Default::default(),
        pins: moving_pins,
        edges: Default::default(),
    };
    // VBD's colouring (cpu::vbd::colouring computes the same).
    topo.colours = std::sync::Arc::new(Colours::from_lists(&Colours::grid(n as usize)));
    Ok((state, topo))
}

/// The particle being dragged with the mouse and where it is dragged to.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Grab {
    /// Particle index.
    pub particle: u32,
    /// Target position, m. The particle is moved there every substep and held.
    pub target: [f32; 3],
}

impl Grab {
    /// `grab` if it names one of `particles` particles and a finite target, else `None`
    /// (what every solver's `set_grab` keeps).
    pub fn checked(grab: Option<Grab>, particles: usize) -> Option<Grab> {
        grab.filter(|g| (g.particle as usize) < particles && g.target.iter().all(|v| v.is_finite()))
    }
}

/// How far along u each cloth of several is moved for the renderers
/// ([`ClothTopology::render_uvs`]): `render.wgsl`'s `CLOTH_UV_STEP`.
pub const RENDER_UV_STEP: f32 = 64.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scenes_velocity_starts_every_free_particle_and_no_pinned_one() {
        let mut scene = Scene::with_n(6);
        scene.cloth.velocity = [0.5, -1.0, 2.0];
        let (state, _) = build_grid(&scene, &SimParams::default()).unwrap();
        let pinned = state.pos.iter().filter(|p| p[3] == 0.0).count();
        assert_eq!(pinned, 2, "the default pins two corners");
        for (p, v) in state.pos.iter().zip(&state.vel) {
            let want = if p[3] == 0.0 { [0.0; 4] } else { [0.5, -1.0, 2.0, 0.0] };
            assert_eq!(*v, want);
        }
    }

    #[test]
    fn counts_match_the_grid() {
        let n = 7u32;
        let (state, topo) = build_grid(&Scene::with_n(n), &SimParams::default()).unwrap();
        let nu = n as usize;
        assert_eq!(state.pos.len(), nu * nu);
        assert_eq!(topo.triangles.len(), 2 * (nu - 1) * (nu - 1));
        // structural 2n(n-1), shear 2(n-1)², bend 2n(n-2)
        let expect = 2 * nu * (nu - 1) + 2 * (nu - 1) * (nu - 1) + 2 * nu * (nu - 2);
        assert_eq!(topo.springs.len(), expect);
        let filled = topo.slots.entries().iter().filter(|s| s.neighbor >= 0).count();
        assert_eq!(filled, 2 * expect, "every spring appears in both ends' slots");
        // Each triangle appears in exactly three face slots.
        let mut seen = vec![0; topo.triangles.len()];
        for f in topo.face_slots.entries().iter().filter(|&&f| f >= 0) {
            seen[*f as usize] += 1;
        }
        assert!(seen.iter().all(|&c| c == 3));
        for p in 0..topo.face_slots.rows() {
            for &t in topo.face_slots.row(p).iter().filter(|&&t| t >= 0) {
                assert!(topo.triangles[t as usize].contains(&(p as u32)));
            }
        }
        let pinned = state.pos.iter().filter(|p| p[3] == 0.0).count();
        assert_eq!(pinned, 2);
    }

    /// What the GPU kernels assume of every grid `build` makes: a regular spring table
    /// (`grid_slots`), and triangles 2q, 2q + 1 of quad q = qj (n - 1) + qi being
    /// (p00, p01, p11) and (p00, p11, p10).
    #[test]
    fn grids_are_regular() {
        for n in [2u32, 3, 5, 8] {
            let (_, mut topo) = build_grid(&Scene::with_n(n), &SimParams::default()).unwrap();
            let g = topo.grid_slots().expect("build makes a regular table");
            assert_eq!(g[0].rest, topo.slots.row(1)[0].rest, "n = {n}: slot 0 from particle 1");
            for (t, tri) in topo.triangles.iter().enumerate() {
                let q = t as u32 / 2;
                let p00 = q / (n - 1) * n + q % (n - 1);
                let want = if t % 2 == 0 { [p00, p00 + n, p00 + n + 1] } else { [p00, p00 + n + 1, p00 + 1] };
                assert_eq!(*tri, want, "n = {n}, triangle {t}");
            }
            // A changed constant, or a neighbour moved, makes the table irregular.
            topo.slots.row_mut(1)[0].ks *= 2.0;
            assert!(topo.grid_slots().is_none(), "n = {n}");
            topo.slots.row_mut(1)[0].ks /= 2.0;
            assert!(topo.grid_slots().is_some());
            topo.slots.row_mut(1)[0].neighbor = -1;
            assert!(topo.grid_slots().is_none(), "n = {n}");
        }
    }
}
