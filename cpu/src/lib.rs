//! clothlab-cpu: the CPU backends and the reference every GPU kernel is checked against —
//! one plain-Rust function per GPU kernel (its twin), in the loop shape the kernel has;
//! the serial and rayon solvers built from them ([`CpuSolver`], `cpu` and `cpu-par`) with
//! the fused SIMD sweep as their one fast path; the contact between triangles as the CPU
//! runs it ([`tri_pipeline`]); and the comparison of any backend with them ([`validate`]).
//! The model they step is `clothlab_core`'s.
//!
//! Every kernel writes each output element from one closure call that reads only its
//! inputs (a gather), so running the loop serially or on rayon's threads computes the
//! same bits. The `*_scatter` functions are the twins of the naive GPU kernels, which
//! walk springs or triangles and accumulate into particles.

#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod adjoint;
mod collide;
mod forces;
mod fused;
pub mod grad;
pub(crate) mod integrate;
mod integrators;
mod lanes;
mod normals;
pub mod self_collide;
mod simd;
mod solver;
mod springs;
mod stats;
mod strain_limit;
pub mod tri_contact;
pub mod tri_pair;
pub mod tri_pipeline;
pub mod validate;
pub mod vbd;

pub use collide::{ColliderSet, Colliders, collide, integrate_collide};
pub use forces::forces;
pub use integrate::integrate;
pub use integrators::{
    AUX, CgScalars, RK2, RK4, RkStage, XPBD_ORDER, XPBD_PASSES, cg_alpha, cg_begin, cg_beta, cg_direction, cg_matvec,
    cg_step, euler, fold, implicit_finish, partial_sums, rk_begin, rk_stage, xpbd_colour, xpbd_mesh_pass, xpbd_pass,
    xpbd_pass_rows,
};
pub use lanes::Lanes;
pub use normals::{FaceLanes, tri_normals, tri_normals_lanes, vertex_normals, vertex_normals_rows};
pub use self_collide::{
    HashBuffers, build_hash, hash_buffers, hash_count, hash_scan_blocks, hash_scan_top, hash_scatter, self_collide,
    self_collide_at,
};
pub use simd::{FUSED_ENV, SIMD_ENV, Simd, fused_from_env};
pub use solver::CpuSolver;
pub use springs::{springs, springs_rows, springs_scatter};
pub use stats::{SubstepStats, particle_stats, substep_stats};
pub use strain_limit::{STRAIN_AIM, strain_count, strain_limit, strain_limit_rows, strain_vel};

use glam::Vec3;
use rayon::prelude::*;

use clothlab_core::grid::V4;

/// What the CPU solvers run a Verlet substep on here, for reports: the fused sweep at
/// the instruction set chosen (by detection or `CLOTHLAB_CPU_SIMD`), or why not.
pub fn fused_path_label() -> String {
    match (fused_from_env(), Simd::from_env()) {
        (Err(e), _) | (_, Err(e)) => e,
        (Ok(false), _) => format!("kernel by kernel ({FUSED_ENV}=off)"),
        (Ok(true), Ok(s)) => format!("fused sweep on {s} (chosen at run time; {SIMD_ENV} picks another)"),
    }
}

/// How a kernel's loop runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Exec {
    /// One thread, index order (the thesis's CPU variant).
    Serial,
    /// rayon's thread pool (the thesis's OpenMP variant).
    Parallel,
}

/// Particles per rayon task: large enough that scheduling costs little next to the work.
const MIN_CHUNK: usize = 1024;

/// Runs `f(i, &mut out[i])` for every element.
pub(crate) fn for_each<T: Send>(exec: Exec, out: &mut [T], f: impl Fn(usize, &mut T) + Sync + Send) {
    match exec {
        Exec::Serial => out.iter_mut().enumerate().for_each(|(i, o)| f(i, o)),
        Exec::Parallel => out.par_iter_mut().with_min_len(MIN_CHUNK).enumerate().for_each(|(i, o)| f(i, o)),
    }
}

/// Runs `f(i, &mut a[i], &mut b[i])` for every element.
pub(crate) fn for_each2<A: Send, B: Send>(
    exec: Exec,
    a: &mut [A],
    b: &mut [B],
    f: impl Fn(usize, &mut A, &mut B) + Sync + Send,
) {
    match exec {
        Exec::Serial => a.iter_mut().zip(b.iter_mut()).enumerate().for_each(|(i, (a, b))| f(i, a, b)),
        Exec::Parallel => a
            .par_iter_mut()
            .zip(b.par_iter_mut())
            .with_min_len(MIN_CHUNK)
            .enumerate()
            .for_each(|(i, (a, b))| f(i, a, b)),
    }
}

/// Runs `f(j, row_j)` for every row of `n` elements of `out`.
pub(crate) fn for_each_row<T: Send>(exec: Exec, n: usize, out: &mut [T], f: impl Fn(usize, &mut [T]) + Sync + Send) {
    match exec {
        Exec::Serial => out.chunks_mut(n).enumerate().for_each(|(j, r)| f(j, r)),
        Exec::Parallel => {
            out.par_chunks_mut(n).with_min_len(MIN_CHUNK.div_ceil(n)).enumerate().for_each(|(j, r)| f(j, r))
        }
    }
}

/// Particles per SIMD group in the interior fast paths.
pub(crate) const LANES: usize = 8;

/// x, y and z of `buf[start .. start + LANES]`, one lane per particle.
#[inline(always)]
pub(crate) fn load3(buf: &[V4], start: usize) -> [wide::f32x8; 3] {
    let g: &[V4; LANES] = buf[start..start + LANES].try_into().expect("LANES elements");
    std::array::from_fn(|c| wide::f32x8::from(std::array::from_fn::<f32, LANES, _>(|k| g[k][c])))
}

/// Writes lanes back as `[x, y, z, 0]` to `buf[0 .. LANES]`.
#[inline(always)]
pub(crate) fn store3(buf: &mut [V4], v: &[wide::f32x8; 3]) {
    let [x, y, z] = [v[0].to_array(), v[1].to_array(), v[2].to_array()];
    for (k, o) in buf[..LANES].iter_mut().enumerate() {
        *o = [x[k], y[k], z[k], 0.0];
    }
}

/// Particles (or faces) read by index: a buffer, a closure, or the fused sweep's rings.
/// A trait rather than `Fn` so that the sweep's readers can be `#[inline(always)]` (a
/// closure is a function of its own, which LLVM did not always inline into the sweep's
/// wide-vector code).
pub(crate) trait Fetch {
    /// Element `k`.
    fn at(&self, k: usize) -> V4;
}

impl<F: Fn(usize) -> V4> Fetch for F {
    #[inline(always)]
    fn at(&self, k: usize) -> V4 {
        self(k)
    }
}

/// The mass of a particle whose position has w = `w` (its relative inverse mass): the
/// reference mass over w, or the reference for a held particle (w = 0). On a grid w is 1
/// or 0, so this is exactly `p.particle_mass` (`m / 1.0` is `m`): the grid's bits do not
/// change.
#[inline(always)]
pub(crate) fn mass(p: &clothlab_core::step_params::StepParams, w: f32) -> f32 {
    if w > 0.0 { p.particle_mass / w } else { p.particle_mass }
}

/// `dt / m` of a particle whose position has w = `w`: `(dt / m̄)·w`, a multiplication
/// where `dt / mass(p, w)` would take a second division per particle and substep; the
/// reference's `dt / m̄` for a held particle (w = 0). `×1.0` on a grid: the grid's bits.
#[inline(always)]
pub(crate) fn dt_over_mass(p: &clothlab_core::step_params::StepParams, w: f32) -> f32 {
    let k = p.dt / p.particle_mass;
    if w > 0.0 { k * w } else { k }
}

#[inline(always)]
pub(crate) fn v3(a: V4) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

#[inline(always)]
pub(crate) fn v4(v: Vec3, w: f32) -> V4 {
    [v.x, v.y, v.z, w]
}
