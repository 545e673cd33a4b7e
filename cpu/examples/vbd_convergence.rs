//! How close each implicit solver gets to implicit Euler's solution per iteration (issue
//! 46): one substep of a hanging cloth in motion, solved by VBD with k sweeps, XPBD with
//! k iterations (its 12 passes each) and implicit Euler with k CG iterations, from the
//! same state; printed is the RMS norm of the gradient of implicit Euler's energy
//! `G(x) = Σ m/(2h²)|x − y|² + Σ ½k(|xᵢ − xⱼ| − r)²` at each result (what all three
//! minimise: VBD by descent on it, XPBD by its constraints of compliance 1/k, the CG by
//! one Newton step of it), relative to its norm at the inertial prediction y, and the
//! time of the substep on the CPU (one thread).
//!
//! `cargo run --release -p clothlab-cpu --example vbd_convergence [n] [units] [substeps]
//! [rho]` (n = 32, units `physical` or `fraction`, the substep 1/60 s over `substeps`, 16;
//! VBD's Chebyshev ρ, 0).

use std::time::Instant;

use clothlab_core::{Integrator, Scene, SimParams, Solver, StiffnessUnits};
use clothlab_cpu::{CpuSolver, Exec};

fn main() {
    let n: u32 = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(32);
    let units = match std::env::args().nth(2).as_deref() {
        Some("fraction") => StiffnessUnits::Fraction,
        _ => StiffnessUnits::Physical,
    };
    let mut scene = Scene::with_n(n);
    (scene.spheres, scene.boxes, scene.floor_y) = (Vec::new(), Vec::new(), None);
    // No damping of any kind, no wind, no strain limit: G is the whole problem.
    let base = SimParams {
        stiffness_units: units,
        air_drag: 0.0,
        damping: 0.0,
        structural_damping: 0.0,
        shear_damping: 0.0,
        bend_damping: 0.0,
        strain_iterations: 0,
        ..SimParams::default()
    };
    // A cloth in motion: half a second of hanging, by VBD with 32 sweeps.
    let mut warm = CpuSolver::new(
        Exec::Parallel,
        scene.clone(),
        SimParams { integrator: Integrator::Vbd, vbd_iterations: 32, ..base.clone() },
    )
    .unwrap();
    for _ in 0..30 {
        warm.step_frame().unwrap();
    }
    let state = warm.state().unwrap();
    // The measured substep: `frame_dt / substeps` (third argument, default 16).
    let substeps: u32 = std::env::args().nth(3).and_then(|s| s.parse().ok()).unwrap_or(16);
    let h = base.frame_dt / substeps as f32;
    // VBD's Chebyshev ρ (fourth argument, default 0: off).
    let rho: f32 = std::env::args().nth(4).and_then(|s| s.parse().ok()).unwrap_or(0.0);
    // One substep of h per "frame".
    let one = SimParams { frame_dt: h, substeps: 1, ..base.clone() };
    let topo = warm.topology().clone();
    let m = base.particle_mass(n) as f64;
    let (h, g) = (h as f64, base.gravity.map(f64::from));
    let free: Vec<bool> = state.pos.iter().map(|x| x[3] != 0.0).collect();
    let y: Vec<[f64; 3]> = state
        .pos
        .iter()
        .zip(&state.vel)
        .map(|(x, v)| std::array::from_fn(|c| x[c] as f64 + h * (v[c] as f64 + h * g[c])))
        .collect();
    // RMS over the free particles of ∇G at `x`.
    let gradient = |x: &[[f64; 3]]| -> f64 {
        let mut grad: Vec<[f64; 3]> =
            x.iter().zip(&y).map(|(x, y)| std::array::from_fn(|c| m / (h * h) * (x[c] - y[c]))).collect();
        for s in &topo.springs {
            let (a, b) = (s.a as usize, s.b as usize);
            let d: [f64; 3] = std::array::from_fn(|c| x[a][c] - x[b][c]);
            let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            if l <= 0.0 {
                continue;
            }
            let t = s.ks as f64 * (l - s.rest as f64) / l;
            for c in 0..3 {
                grad[a][c] += t * d[c];
                grad[b][c] -= t * d[c];
            }
        }
        let (sum, count) = grad
            .iter()
            .zip(&free)
            .filter(|(_, f)| **f)
            .fold((0.0, 0usize), |(s, k), (g, _)| (s + g[0] * g[0] + g[1] * g[1] + g[2] * g[2], k + 1));
        (sum / count.max(1) as f64).sqrt()
    };
    let at_y = gradient(&y);
    println!("n = {n}, {units:?} stiffness, h = {h:.3e} s, VBD's ρ {rho}: ‖∇G‖ at the prediction {at_y:.3e} N");
    println!("| iterations | VBD ‖∇G‖/‖∇G(y)‖ | ms | XPBD | ms | implicit (CG) | ms |");
    println!("|---:|---:|---:|---:|---:|---:|---:|");
    for k in [1u32, 2, 4, 8, 16, 32, 64] {
        let mut row = format!("| {k} |");
        for integrator in [Integrator::Vbd, Integrator::Xpbd, Integrator::Implicit] {
            let p = SimParams {
                integrator,
                vbd_iterations: k,
                vbd_rho: rho,
                xpbd_iterations: k,
                cg_iterations: k,
                ..one.clone()
            };
            let mut s = CpuSolver::new(Exec::Serial, scene.clone(), p).unwrap();
            let mut best = f64::MAX;
            let mut x = Vec::new();
            for _ in 0..3 {
                s.set_state(&state).unwrap();
                let t = Instant::now();
                s.step_frame().unwrap();
                best = best.min(t.elapsed().as_secs_f64() * 1e3);
                x = s.state().unwrap().pos.iter().map(|p| [p[0] as f64, p[1] as f64, p[2] as f64]).collect();
            }
            row.push_str(&format!(" {:.2e} | {best:.2} |", gradient(&x) / at_y));
        }
        println!("{row}");
    }
}
