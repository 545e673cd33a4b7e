//! Checking a GPU backend against the CPU twins: every kernel alone on the same input,
//! and whole rollouts. Used by the cross-backend tests and by `clothlab validate`.

use crate::CpuSolver;
use crate::cpu::{self, Exec};
use crate::grid::{ClothState, ClothTopology, Grab, StepParams, V4};
use crate::params::SimParams;
use crate::scene::Scene;
use crate::solver::{Solver, SolverError};

/// A backend that can run one kernel of its step alone.
pub trait KernelRunner {
    /// The kernels it has, by shader name.
    fn kernel_names(&self) -> Vec<&'static str>;
    /// Runs `kernel` once on `state` and `faces` (one per triangle) with the constants
    /// `p`, and returns the state and faces afterwards (the strain kernel's output as
    /// `pos`). The kernel's pure outputs must be poisoned (NaN) before it runs.
    fn run_kernel(
        &mut self,
        kernel: &str,
        state: &ClothState,
        faces: &[V4],
        p: &StepParams,
    ) -> Result<(ClothState, Vec<V4>), SolverError>;
}

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
    let spacing = scene.cloth.size / (scene.cloth.n - 1) as f32;
    let mut rng = seed;
    let mut rand = move || {
        rng = rng.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((rng >> 40) as f32 / (1u64 << 24) as f32) - 0.5
    };
    for (p, q) in st.pos.iter_mut().zip(st.prev.iter_mut()) {
        if p[3] == 0.0 {
            continue;
        }
        for k in 0..3 {
            p[k] += 0.6 * spacing * rand();
            q[k] = p[k] - 0.4 * spacing * rand();
        }
    }
    for f in st.force.iter_mut() {
        for c in f.iter_mut().take(3) {
            *c = 1e-3 * rand();
        }
    }
    let topo = s.topology().clone();
    let mut faces = vec![[0.0f32; 4]; topo.triangles.len()];
    cpu::tri_normals(Exec::Serial, &topo.triangles, &st.pos, &mut faces);
    Ok((st, topo, faces))
}

/// Per-vertex sums of the adjacent face normals (what the naive scatter accumulates).
pub fn face_sums(topo: &ClothTopology, faces: &[V4]) -> Vec<V4> {
    topo.face_slots
        .iter()
        .map(|slots| {
            let mut s = [0.0f32; 4];
            for &t in slots.iter().filter(|&&t| t >= 0) {
                for k in 0..3 {
                    s[k] += faces[t as usize][k];
                }
            }
            s
        })
        .collect()
}

/// The bound of a kernel, relative to the largest magnitude in the compared buffer:
/// * 1e-5 for per-element kernels: a handful of f32 operations, each within the few ulps
///   Vulkan allows for division and square root (2.5–3 ulp), plus FMA contraction;
/// * 2e-5 for the gathers over up to 12 springs (and the tethers): more operations;
/// * 1e-5 for the atomic scatters: the summation order is arbitrary and spring forces
///   cancel, so rounding is amplified (measured on lavapipe: ≤ 1.4e-7; 0 for gathers,
///   which llvmpipe evaluates in the twins' order).
pub fn kernel_bound(kernel: &str) -> f32 {
    match kernel {
        "springs" | "forces_springs" | "strain_limit" | "vertex_normals" | "vertex_normals_naive" => 2e-5,
        _ => 1e-5,
    }
}

/// Runs every kernel of `runner` alone on a disturbed `n × n` cloth (wind on, a particle
/// grabbed) and compares every buffer with the CPU twins' result.
pub fn validate_kernels(runner: &mut dyn KernelRunner, n: u32, seed: u64) -> Result<Vec<Check>, SolverError> {
    let scene = Scene::with_n(n);
    let params = SimParams { wind: [1.5, 0.3, -2.0], ..SimParams::default() };
    let (st, topo, faces) = disturbed_state(&scene, &params, seed)?;
    let grab = Some(Grab { particle: n * n / 2 + 3, target: [0.1, 1.2, 0.3] });
    let p = StepParams::new(&params, &scene, grab);
    let e = Exec::Serial;
    let mut checks = Vec::new();
    for kernel in runner.kernel_names() {
        let mut input = st.clone();
        // `<name>_imm` is `<name>` reading its constants from immediates, `<name>_tex` is
        // `<name>` reading the spring table from an image: the same twin.
        let base = kernel.trim_end_matches("_imm").trim_end_matches("_tex");
        if base == "vertex_normals_naive" {
            input.normal = face_sums(&topo, &faces);
        }
        let (out, out_faces) = runner.run_kernel(kernel, &input, &faces, &p)?;
        let mut want = input.clone();
        let mut want_faces = faces.clone();
        match base {
            "forces" => cpu::forces(e, &p, &want.pos, &want.prev, &mut want.force),
            "springs" => cpu::springs(e, p.dt, &topo.slots, &want.pos, &want.prev, &mut want.force),
            "forces_springs" => {
                cpu::forces(e, &p, &want.pos, &want.prev, &mut want.force);
                cpu::springs(e, p.dt, &topo.slots, &want.pos, &want.prev, &mut want.force);
            }
            "springs_scatter" | "springs_scatter_f32" => {
                cpu::springs_scatter(p.dt, &topo.springs, &want.pos, &want.prev, &mut want.force)
            }
            "integrate" => cpu::integrate(e, &p, &want.force, &mut want.pos, &mut want.prev),
            "collide" => cpu::collide(e, &p, &scene.spheres, &scene.boxes, &mut want.pos, &mut want.prev),
            "integrate_collide" => {
                cpu::integrate(e, &p, &want.force, &mut want.pos, &mut want.prev);
                cpu::collide(e, &p, &scene.spheres, &scene.boxes, &mut want.pos, &mut want.prev);
            }
            "strain_limit" => {
                let mut o = want.pos.clone();
                cpu::strain_limit(e, &p, &topo.slots, &topo.tethers, &want.pos, &mut o);
                want.pos = o;
            }
            "tri_normals" => cpu::tri_normals(e, &topo.triangles, &want.pos, &mut want_faces),
            "tri_normals_scatter" | "tri_normals_scatter_f32" => {
                cpu::tri_normals(e, &topo.triangles, &want.pos, &mut want_faces);
                want.normal = face_sums(&topo, &want_faces);
            }
            "vertex_normals" | "vertex_normals_naive" => {
                cpu::vertex_normals(e, &p, &topo.face_slots, &faces, &mut want.normal, &mut want.force)
            }
            other => return Err(SolverError::Backend(format!("no CPU twin known for kernel {other}"))),
        }
        let bound = kernel_bound(base);
        checks.push(compare(kernel, "pos", &out.pos, &want.pos, true, bound));
        checks.push(compare(kernel, "prev", &out.prev, &want.prev, true, bound));
        checks.push(compare(kernel, "force", &out.force, &want.force, true, bound));
        checks.push(compare(kernel, "normal", &out.normal, &want.normal, true, bound));
        checks.push(compare(kernel, "faces", &out_faces, &want_faces, true, bound));
    }
    Ok(checks)
}

/// Position error allowed per substep of a rollout, m. Differences start at a few ulps of
/// a position (|x| ≈ 2 m: 2.4e-7 m) per substep and Verlet carries them on as velocity;
/// in a damped, strain-limited cloth they grow about linearly, so 1e-6 m (≈ 4 ulps) per
/// substep. Measured on lavapipe over 208 substeps: optimized 0 (bit-exact), naive 1.5e-5 m.
pub const ROLLOUT_BOUND_PER_SUBSTEP: f32 = 1e-6;

/// Runs `solver` and a serial CPU solver side by side for `frames` frames of the default
/// `n × n` scene and reports the largest position difference.
pub fn validate_rollout(solver: &mut dyn Solver, frames: u32) -> Result<Check, SolverError> {
    let scene = solver.scene().clone();
    let params = solver.params().clone();
    let mut reference = CpuSolver::new(Exec::Serial, scene, params.clone())?;
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
