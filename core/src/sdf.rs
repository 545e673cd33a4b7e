//! Colliders from triangle meshes ("bodies"): a signed distance field on a regular grid,
//! built once when the scene is loaded, sampled trilinearly by the collide kernels.
//!
//! A scene file places a body like a mesh cloth and may move it like any collider:
//!
//! ```toml
//! [[bodies]]
//! mesh = "meshes/mannequin.obj"   # OBJ or glTF, relative to the scene file
//! scale = [1, 1, 1]
//! rotate_deg = [0, 0, 0]
//! translate = [0, 0, 0]
//! resolution = 64                 # cells along the body's longest side (8 … 256)
//! thickness = 0.01                # open meshes only: the shell's half-thickness, m
//! pivot = [0, 1, 0]               # what `spin` turns it about (default: its box's centre)
//! motion = { spin = [0, 1.2, 0] } # as the colliders' motions (`crate::motion`): a spin or
//!                                 # keys' `rotate_deg` turn it about the pivot
//! ```
//!
//! **The field.** The grid covers the placed mesh's bounding box plus a border of
//! [`BORDER_CELLS`] cells (and the thickness); its cells are cubes of side `h` = the longest
//! side / `resolution`. Every grid point holds the exact distance to the nearest triangle
//! (closest point on a triangle, in f64), found by culling triangles block by block
//! (blocks of 4³ points: a triangle whose bounding box is farther from the block than
//! some triangle's farthest point cannot be the nearest of any of its points).
//!
//! **Inside and outside.** A mesh is *closed* when every edge is shared by an even number
//! of triangles (a watertight surface, possibly of several overlapping parts). Then the
//! sign comes from the generalized winding number (the sum of the solid angles the
//! triangles subtend, over 4π; inside where its magnitude exceeds ½), which is robust to
//! overlapping parts (a body whose limbs cross its torso), either orientation, and small
//! cracks, where ray parity would flip; it is computed once per block that no triangle's
//! box touches (the whole block is on one side) and per point elsewhere. An open mesh
//! (a wall, a table top) has no inside: its field is the unsigned distance minus
//! `thickness`, a shell, and `thickness` must be given.
//!
//! **Contact.** A particle whose sampled distance `φ` is below the collision margin is
//! pushed along the field's gradient (the analytic gradient of the trilinear
//! interpolation, normalised) by `margin − φ`, and its velocity relative to the body's
//! surface there loses its normal part into the body and a friction share of the
//! tangential, as for spheres. Outside the grid the body is not felt; a cell whose first
//! value already shows the surface farther than the margin is left after one load
//! ([`BAND_CELLS`]). The field is only as fine as its grid: a cloth settled on a sphere
//! made of triangles lies where it lies on the sphere to a quarter of a cell
//! (`tests/tests/suite/bodies.rs`).
//!
//! **On the GPU** the heads and the grids share one storage buffer of `f32` with the
//! rods ([`crate::layout::Buf::Shapes`]): [`MAX_BODIES`] heads of [`SdfHead::FLOATS`]
//! floats (the bodies' poses at the current substep, rewritten every substep when one
//! moves), the rods (capsules, cylinders) from [`RODS_AT`], every body's values from [`VALUES_AT`]. The
//! CPU twins read the same numbers in the same order.
//!
//! **Speed.** A body is not swept: a scene is refused where a body's surface moves more
//! than [`MAX_CELLS_PER_SUBSTEP`] cells in one substep (its centre's speed plus its
//! fastest turn — a spin or its keys' — times its farthest vertex from the pivot).

use std::path::PathBuf;
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::mesh::{Placement, TriMesh};
use crate::motion::Motion;
use crate::params::{ParamError, finite_in};
use crate::pins::PinPose;

/// Most bodies a scene may hold.
pub const MAX_BODIES: usize = 4;
/// Grid points of border around the mesh's bounding box on every side.
pub const BORDER_CELLS: u32 = 3;
/// Fewest and most cells along a body's longest side.
pub const RESOLUTION_RANGE: (u32, u32) = (8, 256);
/// Default cells along a body's longest side.
pub const DEFAULT_RESOLUTION: u32 = 64;
/// Most grid points of all of a scene's bodies together (64 MiB of f32).
pub const MAX_POINTS: usize = 16 << 20;
/// How far (in cells) a body's surface may move in one substep.
pub const MAX_CELLS_PER_SUBSTEP: f32 = 2.0;
/// Floats of the heads at the start of the GPU's shapes buffer (`Buf::Shapes`).
pub const HEADS_FLOATS: usize = MAX_BODIES * SdfHead::FLOATS;
/// Most rods — capsules, cylinders, every kind together — a scene may hold
/// (`scene::RodRecord`: 16 floats each in the shapes buffer, the kind in `b.w`; as many as
/// spheres or boxes).
pub const MAX_RODS: usize = 16;
/// Where the rods start in the shapes buffer, floats.
pub const RODS_AT: usize = HEADS_FLOATS;
/// Where the bodies' values start in the shapes buffer, floats.
pub const VALUES_AT: usize = RODS_AT + MAX_RODS * 16;

/// A `[[bodies]]` entry of a scene file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// The mesh file (OBJ or glTF), relative to the scene file.
    pub mesh: PathBuf,
    /// Which mesh of a glTF file (default: its first).
    #[serde(default)]
    pub mesh_name: Option<String>,
    /// Scale per axis.
    #[serde(default = "one3")]
    pub scale: [f32; 3],
    /// Rotation about x, y, z, degrees.
    #[serde(default)]
    pub rotate_deg: [f32; 3],
    /// Translation, m.
    #[serde(default)]
    pub translate: [f32; 3],
    /// Cells along the longest side.
    #[serde(default)]
    pub resolution: Option<u32>,
    /// An open mesh's half-thickness, m.
    #[serde(default)]
    pub thickness: Option<f32>,
    /// What a spin turns the body about, m (default: its bounding box's centre).
    #[serde(default)]
    pub pivot: Option<[f32; 3]>,
    /// How it moves.
    #[serde(default)]
    pub motion: Option<Motion>,
}

fn one3() -> [f32; 3] {
    [1.0; 3]
}

impl BodySpec {
    /// Its placement.
    pub fn placement(&self) -> Placement {
        Placement { scale: self.scale, rotate_deg: self.rotate_deg, translate: self.translate }
    }
}

/// A body of a scene: its placed mesh (for drawing and recording), its field, its motion.
#[derive(Debug, Clone, PartialEq)]
pub struct Body {
    /// The placed mesh, at t = 0.
    pub mesh: Arc<TriMesh>,
    /// Its distance field.
    pub sdf: Arc<SdfGrid>,
    /// The spin's centre, m (the field's local origin).
    pub pivot: [f32; 3],
    /// Its motion (default: still).
    pub motion: Motion,
}

impl Body {
    /// A body from a placed mesh: its field at `resolution` cells along the longest side
    /// (`thickness` for an open mesh), turning about `pivot` (default the box's centre).
    pub fn new(
        mesh: TriMesh,
        resolution: u32,
        thickness: Option<f32>,
        pivot: Option<[f32; 3]>,
        motion: Motion,
    ) -> Result<Self, String> {
        let (lo, hi) = bounds(&mesh)?;
        let pivot = pivot.unwrap_or([0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])]);
        let sdf = SdfGrid::build(&mesh, pivot, resolution, thickness)?;
        Ok(Self { mesh: Arc::new(mesh), sdf: Arc::new(sdf), pivot, motion })
    }

    /// Its pose at time `t`, s.
    pub fn head_at(&self, t: f64, offset: u32) -> SdfHead {
        let pose = PinPose::at(&self.motion, self.pivot, t);
        let g = &self.sdf;
        SdfHead {
            cols: pose.cols,
            translation: pose.translation,
            velocity: pose.velocity,
            spin: pose.spin,
            lo: [g.lo[0], g.lo[1], g.lo[2], g.h],
            dims: [g.dims[0], g.dims[1], g.dims[2], offset],
        }
    }

    /// The field at world point `x` at time `t`, s (`None` outside its grid): what the
    /// contacts sample, for tests and tools.
    pub fn distance(&self, x: [f32; 3], t: f64) -> Option<f32> {
        let hd = self.head_at(t, 0);
        let d = [0, 1, 2].map(|k| x[k] - hd.translation[k]);
        let q = hd.cols.map(|c| c[0] * d[0] + c[1] * d[1] + c[2] * d[2]);
        self.sdf.sample(q).map(|(phi, _)| phi)
    }

    /// Its mesh's vertices at time `t`, s (`R·(x − pivot) + translation`).
    pub fn posed_at(&self, t: f64) -> Vec<[f32; 3]> {
        let pose = PinPose::at(&self.motion, self.pivot, t);
        let c = |k: usize| glam::Vec3::from_slice(&pose.cols[k][..3]);
        let tr = glam::Vec3::from_slice(&pose.translation[..3]);
        let pivot = glam::Vec3::from(self.pivot);
        self.mesh
            .positions
            .iter()
            .map(|&p| {
                let q = glam::Vec3::from(p) - pivot;
                (c(0) * q.x + c(1) * q.y + c(2) * q.z + tr).to_array()
            })
            .collect()
    }

    /// The farthest vertex from the pivot, m.
    pub fn reach(&self) -> f32 {
        let d = |p: &[f32; 3]| (0..3).map(|k| (p[k] - self.pivot[k]).powi(2)).sum::<f32>().sqrt();
        self.mesh.positions.iter().map(d).fold(0.0, f32::max)
    }

    /// Refuses a motion whose surface moves more than [`MAX_CELLS_PER_SUBSTEP`] cells in a
    /// substep of `dt` s.
    pub fn check_speed(&self, field: &str, dt: f32) -> Result<(), ParamError> {
        let speed = self.motion.max_speed() + self.motion.max_turn_rate() * self.reach();
        let limit = MAX_CELLS_PER_SUBSTEP * self.sdf.h;
        if speed * dt > limit {
            return Err(ParamError::new(
                format!("{field}.motion"),
                format!("{speed} m/s"),
                format!(
                    "its surface moves {:.4} m per substep of {dt:.5} s at its fastest; a body's field resolves at most {MAX_CELLS_PER_SUBSTEP} cells ({limit:.4} m) a substep: slow it or raise params.substeps",
                    speed * dt
                ),
            ));
        }
        Ok(())
    }
}

/// A body's pose at one substep and where its grid lies (WGSL: 32 floats of the `sdf`
/// buffer, read by `body_contact`). World `x = R·q + translation` for a point `q` of the
/// grid's frame; grid point `(i, j, k)` is at `q = lo + h·(i, j, k)`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SdfHead {
    /// R's columns (w 0).
    pub cols: [[f32; 4]; 3],
    /// The pivot moved by the motion, m (w 0).
    pub translation: [f32; 4],
    /// The motion's velocity, m/s (w 0).
    pub velocity: [f32; 4],
    /// The angular velocity, rad/s (w 0).
    pub spin: [f32; 4],
    /// The grid's first point in the body's frame, m; w the cell size h.
    pub lo: [f32; 4],
    /// Points per axis; w the first value's index among the grids' values.
    pub dims: [u32; 4],
}

impl SdfHead {
    /// Floats a head takes in the GPU buffer.
    pub const FLOATS: usize = 32;
}

/// A signed distance field on a grid of points (x fastest, then y, then z).
#[derive(Debug, Clone, PartialEq)]
pub struct SdfGrid {
    /// The first point, relative to the pivot, m.
    pub lo: [f32; 3],
    /// The spacing, m.
    pub h: f32,
    /// Points per axis (each ≥ 2).
    pub dims: [u32; 3],
    /// Distances, m: negative inside a closed mesh; an open mesh's shell: the distance
    /// minus its thickness.
    pub values: Vec<f32>,
    /// Whether the mesh was closed.
    pub closed: bool,
}

fn bounds(mesh: &TriMesh) -> Result<([f32; 3], [f32; 3]), String> {
    if mesh.triangles.is_empty() {
        return Err("the mesh has no triangles".into());
    }
    let n = mesh.positions.len() as u32;
    if let Some(t) = mesh.triangles.iter().find(|t| t.iter().any(|&v| v >= n)) {
        return Err(format!("a triangle {t:?} names a vertex past the last ({n})"));
    }
    if mesh.positions.iter().flatten().any(|v| !v.is_finite() || v.abs() > 1e4) {
        return Err("a vertex is not finite or lies farther than 10 km".into());
    }
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for t in &mesh.triangles {
        for &v in t {
            let p = mesh.positions[v as usize];
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    let ext = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f32::max);
    if ext <= 1e-6 {
        return Err("the mesh's triangles have no extent".into());
    }
    Ok((lo, hi))
}

type D3 = [f64; 3];

fn sub(a: D3, b: D3) -> D3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: D3, b: D3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: D3, b: D3) -> D3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
fn len(a: D3) -> f64 {
    dot(a, a).sqrt()
}

/// Squared distance from `p` to triangle `abc` (Ericson, Real-Time Collision Detection,
/// 5.1.5: the closest point by Voronoi regions).
fn tri_dist2(p: D3, a: D3, b: D3, c: D3) -> f64 {
    let ab = sub(b, a);
    let ac = sub(c, a);
    let ap = sub(p, a);
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return dot(ap, ap);
    }
    let bp = sub(p, b);
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return dot(bp, bp);
    }
    let at = |v: f64, w: f64| {
        let q = [a[0] + ab[0] * v + ac[0] * w, a[1] + ab[1] * v + ac[1] * w, a[2] + ab[2] * v + ac[2] * w];
        let d = sub(p, q);
        dot(d, d)
    };
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return at(d1 / (d1 - d3), 0.0);
    }
    let cp = sub(p, c);
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return dot(cp, cp);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return at(0.0, d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        let q = [b[0] + (c[0] - b[0]) * w, b[1] + (c[1] - b[1]) * w, b[2] + (c[2] - b[2]) * w];
        let d = sub(p, q);
        return dot(d, d);
    }
    let denom = 1.0 / (va + vb + vc);
    at(vb * denom, vc * denom)
}

/// The solid angle triangle `abc` subtends at `p` (Van Oosterom and Strackee), signed by
/// its orientation.
fn solid_angle(p: D3, a: D3, b: D3, c: D3) -> f64 {
    let (a, b, c) = (sub(a, p), sub(b, p), sub(c, p));
    let (la, lb, lc) = (len(a), len(b), len(c));
    let num = dot(a, cross(b, c));
    let den = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb;
    2.0 * num.atan2(den)
}

/// Whether every edge of `mesh` is shared by an even number of triangles.
pub fn is_closed(mesh: &TriMesh) -> bool {
    let mut edges: Vec<(u32, u32)> = mesh
        .triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    edges.sort_unstable();
    edges.chunk_by(|x, y| x == y).all(|run| run.len() % 2 == 0)
}

const BLOCK: u32 = 4;

impl SdfGrid {
    /// The field of placed `mesh` in the frame of `pivot` (see the module's documentation).
    pub fn build(mesh: &TriMesh, pivot: [f32; 3], resolution: u32, thickness: Option<f32>) -> Result<Self, String> {
        use rayon::prelude::*;
        let (rmin, rmax) = RESOLUTION_RANGE;
        if !(rmin..=rmax).contains(&resolution) {
            return Err(format!("resolution {resolution}: from {rmin} to {rmax} cells along the longest side"));
        }
        let (lo_m, hi_m) = bounds(mesh)?;
        let closed = is_closed(mesh);
        let shell = match (closed, thickness) {
            (true, None) => 0.0,
            (true, Some(_)) => {
                return Err("thickness is for open meshes; this one is closed (its inside is solid)".into());
            }
            (false, None) => {
                return Err("the mesh is open (an edge belongs to one triangle): give its thickness, m".into());
            }
            (false, Some(t)) if !(t.is_finite() && t > 0.0 && t <= 1.0) => {
                return Err(format!("thickness {t}: an open mesh's half-thickness, above 0 and at most 1 m"));
            }
            (false, Some(t)) => t,
        };
        let ext = (0..3).map(|k| hi_m[k] - lo_m[k]).fold(0.0, f32::max);
        let h = ext / resolution as f32;
        let border = BORDER_CELLS as f32 * h + shell;
        let mut lo = [0.0f32; 3];
        let mut dims = [0u32; 3];
        for k in 0..3 {
            lo[k] = lo_m[k] - border - pivot[k];
            dims[k] = ((hi_m[k] - lo_m[k] + 2.0 * border) / h).ceil() as u32 + 1;
        }
        let points = dims.iter().map(|&d| d as usize).product::<usize>();
        if points > MAX_POINTS {
            return Err(format!("{dims:?} grid points are more than {MAX_POINTS}: lower the resolution"));
        }
        let tris: Vec<[D3; 3]> = mesh
            .triangles
            .iter()
            .map(|t| t.map(|v| std::array::from_fn(|k| mesh.positions[v as usize][k] as f64 - pivot[k] as f64)))
            .collect();
        let boxes: Vec<(D3, D3)> = tris
            .iter()
            .map(|t| {
                let lo = std::array::from_fn(|k| t[0][k].min(t[1][k]).min(t[2][k]));
                let hi = std::array::from_fn(|k| t[0][k].max(t[1][k]).max(t[2][k]));
                (lo, hi)
            })
            .collect();
        let point = |i: u32, j: u32, k: u32| -> D3 {
            [lo[0] as f64 + h as f64 * i as f64, lo[1] as f64 + h as f64 * j as f64, lo[2] as f64 + h as f64 * k as f64]
        };
        let winding =
            |p: D3| tris.iter().map(|t| solid_angle(p, t[0], t[1], t[2])).sum::<f64>() / (4.0 * std::f64::consts::PI);
        let nb = dims.map(|d| d.div_ceil(BLOCK));
        // Each block's points: (index, value).
        let blocks: Vec<Vec<(usize, f32)>> = (0..nb[0] * nb[1] * nb[2])
            .into_par_iter()
            .map(|b| {
                let (bi, bj, bk) = (b % nb[0], (b / nb[0]) % nb[1], b / (nb[0] * nb[1]));
                let first = [bi * BLOCK, bj * BLOCK, bk * BLOCK];
                let last: [u32; 3] = std::array::from_fn(|a| (first[a] + BLOCK - 1).min(dims[a] - 1));
                let (blo, bhi) = (point(first[0], first[1], first[2]), point(last[0], last[1], last[2]));
                let centre: D3 = std::array::from_fn(|a| 0.5 * (blo[a] + bhi[a]));
                let half = 0.5 * len(sub(bhi, blo));
                // The nearest triangle of any point is within `bound` of the block.
                let bound = tris
                    .iter()
                    .map(|t| tri_dist2(centre, t[0], t[1], t[2]).sqrt() + half)
                    .fold(f64::INFINITY, f64::min);
                let gap = |(tlo, thi): &(D3, D3)| {
                    let d: D3 = std::array::from_fn(|a| (tlo[a] - bhi[a]).max(blo[a] - thi[a]).max(0.0));
                    len(d)
                };
                let near: Vec<usize> = (0..tris.len()).filter(|&t| gap(&boxes[t]) <= bound).collect();
                let touched = boxes.iter().any(|b| gap(b) == 0.0);
                let block_inside = closed && !touched && winding(centre).abs() > 0.5;
                let mut out = Vec::with_capacity((BLOCK * BLOCK * BLOCK) as usize);
                for k in first[2]..=last[2] {
                    for j in first[1]..=last[1] {
                        for i in first[0]..=last[0] {
                            let p = point(i, j, k);
                            let d2 = near
                                .iter()
                                .map(|&t| tri_dist2(p, tris[t][0], tris[t][1], tris[t][2]))
                                .fold(f64::INFINITY, f64::min);
                            let d = d2.sqrt();
                            let phi = if !closed {
                                d - shell as f64
                            } else if (touched && winding(p).abs() > 0.5) || block_inside {
                                -d
                            } else {
                                d
                            };
                            let idx = i as usize + dims[0] as usize * (j as usize + dims[1] as usize * k as usize);
                            out.push((idx, phi as f32));
                        }
                    }
                }
                out
            })
            .collect();
        let mut values = vec![0.0f32; points];
        for (idx, v) in blocks.into_iter().flatten() {
            values[idx] = v;
        }
        Ok(Self { lo, h, dims, values, closed })
    }

    /// The field and its (unnormalised) gradient at `q` in the grid's frame, trilinearly
    /// from the 8 points around it; `None` outside the grid. (The kernels' `body_contact`
    /// samples the same way; this is for tests and tools.)
    pub fn sample(&self, q: [f32; 3]) -> Option<(f32, [f32; 3])> {
        sample_grid(&[self.lo[0], self.lo[1], self.lo[2], self.h], self.dims, &self.values, q, f32::INFINITY)
    }
}

/// How far below its cell's first value the field can be anywhere in the cell, in cells:
/// the values are distances (1-Lipschitz), so the 8 corners lie within √3 h of the first
/// and their trilinear blend too; 1.75 > √3 covers the values' rounding.
pub const BAND_CELLS: f32 = 1.75;

/// Trilinear sample of a grid `values` at `q` (frame of `lo`, w the spacing), with the
/// gradient of the interpolant (not divided by h): the order of operations the WGSL's
/// `body_sample` keeps. `None` outside the grid, and where the cell's first value shows
/// the field is at least `reach` all over the cell (one load instead of eight for a
/// particle away from the surface: [`BAND_CELLS`]).
#[inline(always)]
pub(crate) fn sample_grid(
    lo: &[f32; 4],
    dims: [u32; 3],
    values: &[f32],
    q: [f32; 3],
    reach: f32,
) -> Option<(f32, [f32; 3])> {
    let g = [(q[0] - lo[0]) / lo[3], (q[1] - lo[1]) / lo[3], (q[2] - lo[2]) / lo[3]];
    let top = [(dims[0] - 1) as f32, (dims[1] - 1) as f32, (dims[2] - 1) as f32];
    // `!(a && b)`: a NaN is outside.
    if !(g[0] >= 0.0 && g[1] >= 0.0 && g[2] >= 0.0 && g[0] <= top[0] && g[1] <= top[1] && g[2] <= top[2]) {
        return None;
    }
    let c = [g[0].floor().min(top[0] - 1.0), g[1].floor().min(top[1] - 1.0), g[2].floor().min(top[2] - 1.0)];
    let f = [g[0] - c[0], g[1] - c[1], g[2] - c[2]];
    let (sx, sy) = (1usize, dims[0] as usize);
    let sz = sy * dims[1] as usize;
    let base = c[0] as usize + sy * c[1] as usize + sz * c[2] as usize;
    let v = |o: usize| values.get(base + o).copied().unwrap_or(0.0);
    let c000 = v(0);
    if c000 - BAND_CELLS * lo[3] >= reach {
        return None;
    }
    let (c100, c010, c110) = (v(sx), v(sy), v(sx + sy));
    let (c001, c101, c011, c111) = (v(sz), v(sx + sz), v(sy + sz), v(sx + sy + sz));
    let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
    let phi = lerp(
        lerp(lerp(c000, c100, f[0]), lerp(c010, c110, f[0]), f[1]),
        lerp(lerp(c001, c101, f[0]), lerp(c011, c111, f[0]), f[1]),
        f[2],
    );
    let gx = lerp(lerp(c100 - c000, c110 - c010, f[1]), lerp(c101 - c001, c111 - c011, f[1]), f[2]);
    let gy = lerp(lerp(c010 - c000, c110 - c100, f[0]), lerp(c011 - c001, c111 - c101, f[0]), f[2]);
    let gz = lerp(lerp(c001 - c000, c101 - c100, f[0]), lerp(c011 - c010, c111 - c110, f[0]), f[1]);
    Some((phi, [gx, gy, gz]))
}

/// The bodies' heads and grids as the collide kernels read them.
#[derive(Debug, Clone, Copy, Default)]
pub struct Bodies<'a> {
    /// One head per body, at the current substep.
    pub heads: &'a [SdfHead],
    /// Every body's values, one after another (a head's `dims[3]` is its first).
    pub values: &'a [f32],
}

/// Checks a scene's bodies' placement fields (finite, sensible).
pub fn check_spec(spec: &BodySpec, field: &str) -> Result<(), ParamError> {
    for v in spec.scale {
        finite_in(format!("{field}.scale"), v, 1e-4, 1e4)?;
    }
    for v in spec.rotate_deg {
        finite_in(format!("{field}.rotate_deg"), v, -3600.0, 3600.0)?;
    }
    for v in spec.translate {
        finite_in(format!("{field}.translate"), v, -1e4, 1e4)?;
    }
    for v in spec.pivot.unwrap_or_default() {
        finite_in(format!("{field}.pivot"), v, -1e4, 1e4)?;
    }
    if let Some(m) = &spec.motion {
        m.check(field, true)?;
    }
    Ok(())
}

/// Every body's values, one after another, and each one's first index.
pub fn concat(bodies: &[Body]) -> (Vec<f32>, Vec<u32>) {
    let mut values = Vec::new();
    let mut firsts = Vec::new();
    for b in bodies {
        firsts.push(values.len() as u32);
        values.extend_from_slice(&b.sdf.values);
    }
    (values, firsts)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An icosphere of radius `r` about `c`, subdivided `levels` times.
    pub(crate) fn icosphere(c: [f32; 3], r: f32, levels: u32) -> TriMesh {
        let t = (1.0 + 5f32.sqrt()) / 2.0;
        let mut p: Vec<[f32; 3]> = vec![
            [-1.0, t, 0.0],
            [1.0, t, 0.0],
            [-1.0, -t, 0.0],
            [1.0, -t, 0.0],
            [0.0, -1.0, t],
            [0.0, 1.0, t],
            [0.0, -1.0, -t],
            [0.0, 1.0, -t],
            [t, 0.0, -1.0],
            [t, 0.0, 1.0],
            [-t, 0.0, -1.0],
            [-t, 0.0, 1.0],
        ];
        let mut f: Vec<[u32; 3]> = vec![
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ];
        for _ in 0..levels {
            let mut mid = std::collections::HashMap::new();
            let mut next = Vec::new();
            for tri in &f {
                let mut m = [0u32; 3];
                for e in 0..3 {
                    let (a, b) = (tri[e], tri[(e + 1) % 3]);
                    m[e] = *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                        let (pa, pb) = (p[a as usize], p[b as usize]);
                        p.push([(pa[0] + pb[0]) / 2.0, (pa[1] + pb[1]) / 2.0, (pa[2] + pb[2]) / 2.0]);
                        p.len() as u32 - 1
                    });
                }
                next.extend([[tri[0], m[0], m[2]], [tri[1], m[1], m[0]], [tri[2], m[2], m[1]], m]);
            }
            f = next;
        }
        let positions = p
            .iter()
            .map(|v| {
                let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                [c[0] + r * v[0] / l, c[1] + r * v[1] / l, c[2] + r * v[2] / l]
            })
            .collect();
        TriMesh { positions, uvs: None, triangles: f }
    }

    #[test]
    fn icosphere_field_is_the_sphere_distance() {
        // Radius 0.5, 1280 triangles: the faceting's deepest gap (the centre of a face)
        // is r(1 − cos θ) with θ ≈ the face's circumradius angle, ≈ 3 mm at 0.5 m.
        let mesh = icosphere([0.2, 1.0, -0.3], 0.5, 3);
        assert!(is_closed(&mesh));
        let body = Body::new(mesh, 32, None, None, Motion::default()).unwrap();
        let g = &body.sdf;
        assert!(g.closed);
        let mut worst = 0.0f32;
        for (idx, &v) in g.values.iter().enumerate() {
            let d = g.dims.map(|d| d as usize);
            let (i, j, k) = (idx % d[0], (idx / d[0]) % d[1], idx / (d[0] * d[1]));
            let q = [g.lo[0] + g.h * i as f32, g.lo[1] + g.h * j as f32, g.lo[2] + g.h * k as f32];
            let exact = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt() - 0.5;
            worst = worst.max((v - exact).abs());
        }
        // Grid points: exact distances to the faceted sphere, within its faceting (8 mm
        // for 1280 faces of a 0.5 m sphere; inside, the nearest face is farther than the
        // sphere by up to that).
        assert!(worst < 8e-3, "worst grid point {worst} m off the sphere's distance");
        // Between points: trilinear, the gradient the outward normal.
        let (phi, grad) = g.sample([0.0, 0.41, 0.03]).unwrap();
        let exact = (0.41f32 * 0.41 + 0.03 * 0.03).sqrt() - 0.5;
        assert!((phi - exact).abs() < 1e-2, "sampled {phi} vs {exact}");
        let l = (grad[0] * grad[0] + grad[1] * grad[1] + grad[2] * grad[2]).sqrt();
        assert!(grad[1] / l > 0.99, "normal {grad:?} points up and out");
        assert!(g.sample([5.0, 0.0, 0.0]).is_none());
        assert!(g.sample([f32::NAN, 0.0, 0.0]).is_none());
    }

    #[test]
    fn open_meshes_need_a_thickness_and_bad_meshes_are_refused() {
        let quad = TriMesh {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 1.0], [0.0, 0.0, 1.0]],
            uvs: None,
            triangles: vec![[0, 2, 1], [0, 3, 2]],
        };
        assert!(!is_closed(&quad));
        let e = Body::new(quad.clone(), 16, None, None, Motion::default()).unwrap_err();
        assert!(e.contains("open"), "{e}");
        let b = Body::new(quad.clone(), 16, Some(0.02), None, Motion::default()).unwrap();
        // Above the quad's middle by 0.1 m: 0.1 − 0.02 (a grid point: exact to rounding).
        let (phi, _) = b.sdf.sample([0.0, 0.1, 0.0]).unwrap();
        assert!((phi - 0.08).abs() < 1e-5, "{phi}");
        assert!(Body::new(quad.clone(), 4, Some(0.02), None, Motion::default()).is_err());
        let mut nan = quad.clone();
        nan.positions[0][1] = f32::NAN;
        assert!(Body::new(nan, 16, Some(0.02), None, Motion::default()).is_err());
        let mut far = quad;
        far.triangles[0][1] = 9;
        assert!(Body::new(far, 16, Some(0.02), None, Motion::default()).is_err());
        let sphere = icosphere([0.0; 3], 1.0, 1);
        assert!(Body::new(sphere, 16, Some(0.1), None, Motion::default()).unwrap_err().contains("closed"));
    }

    #[test]
    fn overlapping_parts_and_either_orientation_are_solid() {
        // Two overlapping spheres (a limb through a torso): the overlap has winding 2,
        // where ray parity would call it outside.
        let a = icosphere([0.0, 0.0, 0.0], 0.5, 2);
        let b = icosphere([0.4, 0.0, 0.0], 0.5, 2);
        let off = a.positions.len() as u32;
        let mut m = a.clone();
        m.positions.extend(&b.positions);
        m.triangles.extend(b.triangles.iter().map(|t| t.map(|v| v + off)));
        let body = Body::new(m, 32, None, Some([0.0; 3]), Motion::default()).unwrap();
        // The overlap's middle: 0.3 m from both surfaces (within the grid's 1.5 cm
        // faceting and interpolation).
        let (phi, _) = body.sdf.sample([0.2, 0.0, 0.0]).unwrap();
        assert!((phi + 0.3).abs() < 0.02, "inside both parts: {phi}");
        // A sphere turned inside out (clockwise triangles) is solid all the same.
        let mut inv = icosphere([0.0; 3], 0.5, 2);
        for t in &mut inv.triangles {
            t.swap(1, 2);
        }
        let body = Body::new(inv, 32, None, Some([0.0; 3]), Motion::default()).unwrap();
        let (phi, _) = body.sdf.sample([0.1, 0.0, 0.0]).unwrap();
        assert!((phi + 0.4).abs() < 0.02, "inside the reversed sphere: {phi}");
    }
}
