//! Comparing a backend with the CPU reference: the measure ([`compare`], [`Check`]), the
//! disturbed input of the kernel checks, and whole rollouts. The kernel-by-kernel checks
//! and the bisection run through the kernel registry in `clothlab_engine::validate`.

use crate::CpuSolver;
use crate::Exec;
use clothlab_core::grid::{ClothState, ClothTopology, V4};
use clothlab_core::params::SimParams;
use clothlab_core::scene::Scene;
use clothlab_core::solver::{Solver, SolverError};

/// One line of a validation report.
#[derive(Debug, Clone, PartialEq)]
pub struct Check {
    /// Kernel name, or `rollout N` for a whole run.
    pub what: String,
    /// The buffer compared.
    pub buffer: &'static str,
    /// Largest absolute difference (NaN counts as infinite).
    pub max_abs: f32,
    /// Root-mean-square difference.
    pub rms: f32,
    /// The value compared with `bound`: `max_abs / max |reference|` for kernels, `max_abs`
    /// in metres for rollouts.
    pub error: f32,
    /// The bound `error` must not exceed.
    pub bound: f32,
}

impl Check {
    /// Within the bound.
    pub fn passed(&self) -> bool {
        self.error <= self.bound
    }
}

/// Compares the xyz components of two buffers.
pub fn compare(what: &str, buffer: &'static str, got: &[V4], want: &[V4], relative: bool, bound: f32) -> Check {
    let mut max_abs = 0.0f32;
    let mut sum2 = 0.0f64;
    let mut scale = 0.0f32;
    let mut count = 0usize;
    for (g, w) in got.iter().zip(want) {
        for k in 0..3 {
            let d = (g[k] - w[k]).abs();
            let d = if d.is_nan() { f32::INFINITY } else { d };
            max_abs = max_abs.max(d);
            sum2 += (d as f64) * (d as f64);
            scale = scale.max(w[k].abs());
            count += 1;
        }
    }
    if got.len() != want.len() {
        max_abs = f32::INFINITY;
    }
    let rms = if count > 0 { (sum2 / count as f64).sqrt() as f32 } else { 0.0 };
    let error = if relative && scale > 0.0 { max_abs / scale } else { max_abs };
    Check { what: what.to_owned(), buffer, max_abs, rms, error, bound }
}

/// A draped, then randomly disturbed state (seeded): positions moved by up to ±0.3
/// spacing, velocities up to ±0.2 spacing per substep, small random forces. Returns it with
/// its topology and its face normals.
pub fn disturbed_state(
    scene: &Scene,
    params: &SimParams,
    seed: u64,
) -> Result<(ClothState, ClothTopology, Vec<V4>), SolverError> {
    let mut s = CpuSolver::new(Exec::Serial, scene.clone(), params.clone())?;
    for _ in 0..15 {
        s.step_frame()?;
    }
    let mut st = s.state()?;
    // The grid's spacing, or a mesh's mean edge length.
    let spacing = s.topology().spacing;
    let mut rng = seed;
    let mut rand = move || {
        rng = rng.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((rng >> 40) as f32 / (1u64 << 24) as f32) - 0.5
    };
    let dt = params.dt();
    for (p, q) in st.pos.iter_mut().zip(st.vel.iter_mut()) {
        if p[3] == 0.0 {
            continue;
        }
        for k in 0..3 {
            p[k] += 0.6 * spacing * rand();
            q[k] = 0.4 * spacing * rand() / dt;
        }
    }
    for f in st.force.iter_mut() {
        for c in f.iter_mut().take(3) {
            *c = 1e-3 * rand();
        }
    }
    let topo = s.topology().clone();
    let mut faces = vec![[0.0f32; 4]; topo.triangles.len()];
    crate::tri_normals(Exec::Serial, &topo.triangles, &st.pos, &mut faces);
    Ok((st, topo, faces))
}

/// Position error allowed per substep of a rollout, m. Differences start at a few ulps of
/// a position (|x| ≈ 2 m: 2.4e-7 m) per substep and the strain limit carries them on as
/// velocity;
/// in a damped, strain-limited cloth they grow about linearly, so 1e-6 m (≈ 4 ulps) per
/// substep. Measured on lavapipe over 208 substeps: optimized 0 (bit-exact), naive 1.5e-5 m.
pub const ROLLOUT_BOUND_PER_SUBSTEP: f32 = 1e-6;

/// Runs `solver` and a serial CPU solver side by side for `frames` frames of the default
/// `n × n` scene and reports the largest position difference.
pub fn validate_rollout(solver: &mut dyn Solver, frames: u32) -> Result<Check, SolverError> {
    let scene = solver.scene().clone();
    let params = solver.params().clone();
    let mut reference = CpuSolver::new(Exec::Serial, scene, params.clone())?;
    // Moving colliders: the reference's at the solver's time.
    reference.set_time(solver.time())?;
    let mut worst = compare("", "pos", &[], &[], false, 0.0);
    for _ in 0..frames {
        reference.step_frame()?;
        solver.step_frame()?;
        let c = compare("", "pos", &solver.state()?.pos, &reference.state_ref().pos, false, 0.0);
        if c.max_abs > worst.max_abs {
            worst = c;
        }
    }
    let steps = frames * params.substeps;
    Ok(Check {
        what: format!("rollout {steps}"),
        bound: ROLLOUT_BOUND_PER_SUBSTEP * steps as f32,
        error: worst.max_abs,
        ..worst
    })
}
