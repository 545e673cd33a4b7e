//! Every integrator on every GPU API against the CPU solver (which computes the bits of
//! the CPU engine's recipes: engine/tests/suite/integrators.rs), in a rollout, under the
//! Vulkan validation layer; and an integrator switched while running. The kernels themselves
//! are checked one by one against their twins with every other kernel
//! (`validate::flavors` lists them: api_vs_cpu.rs).

use clothlab_core::{Integrator, Scene, SimParams, Solver};
use clothlab_cpu::validate::validate_rollout;
use clothlab_engine::Variant;
use clothlab_tests::{Api, assert_api_clean, or_skip};
use clothlab_wgpu::{SolverOptions, wgpu_solver};

/// Soft springs with heavy damping (Σζ > Σκ), so that explicit Euler and the midpoint
/// method may run too; wind on, two strain passes.
fn params(integrator: Integrator) -> SimParams {
    SimParams {
        integrator,
        wind: [2.0, 0.0, 1.0],
        strain_iterations: 2,
        // Two Gauss–Seidel iterations: λ carried from one to the next.
        xpbd_iterations: 2,
        ..SimParams::default()
    }
    .with_soft_springs()
}

/// The recipes the rollouts below run: one row per API, both recipes among them.
const ROWS: [(Api, Variant); 3] =
    [(Api::Wgpu, Variant::OPTIMIZED), (Api::Vulkan, Variant::NAIVE), (Api::Gl, Variant::OPTIMIZED)];

#[test]
fn every_integrator_on_every_gpu_api_follows_the_cpu_within_the_rollout_bound() {
    // 48 substeps of a 40 × 40 cloth (a grid that is not a multiple of the workgroup):
    // the rollout bound is 1e-6 m per substep, as for Verlet — the CG dot products are
    // summed in another order on the GPU, which the bound covers. What this adds to the
    // kernels' own checks (api_vs_cpu.rs) is each integrator's order of kernels on each API:
    // a kernel left out, run twice or out of order moves the cloth by more than the bound
    // from the first substep on (a skipped RK stage: millimetres), so 48 substeps see what
    // 96 did, with a bound half as wide.
    let frames = 3;
    let scene = Scene::with_n(40);
    for integrator in Integrator::ALL {
        let p = params(integrator);
        for (api, variant) in ROWS {
            let Some(mut s) = api.solver(variant, &scene, &p) else { return };
            let name = format!("{} {}", api.name(), variant.label());
            let c = validate_rollout(&mut *s, frames).unwrap();
            println!(
                "{:17} {name:16} rollout {} max {:.2e} m (bound {:.0e})",
                integrator.name(),
                c.what,
                c.error,
                c.bound
            );
            assert!(c.passed(), "{} on {name}: {:e} m from the CPU (bound {:e})", integrator.name(), c.error, c.bound);
            assert_api_clean(&mut *s);
        }
    }
}

#[test]
fn switching_the_integrator_while_running_keeps_the_cloth_and_the_gpu_on_the_cpu() {
    // Verlet, then RK4, then implicit, then XPBD, then VBD with its Chebyshev acceleration,
    // on wgpu and on the CPU side by side: the GPU solver builds the new recipe's kernels
    // when the parameters change.
    let scene = Scene::with_n(24);
    let p = params(Integrator::Verlet);
    let Some(mut g) =
        or_skip(wgpu_solver(Variant::OPTIMIZED, scene.clone(), p.clone(), SolverOptions::default()), "wgpu")
    else {
        return;
    };
    let mut c = clothlab_cpu::CpuSolver::new(clothlab_cpu::Exec::Serial, scene, p.clone()).unwrap();
    let switches = [Integrator::Rk4, Integrator::Implicit, Integrator::Xpbd, Integrator::Vbd];
    for (k, integrator) in switches.into_iter().enumerate() {
        for s in [&mut g as &mut dyn Solver, &mut c] {
            s.set_params(SimParams { vbd_rho: 0.9, ..params(integrator) }).unwrap();
            for _ in 0..2 {
                s.step_frame().unwrap();
            }
        }
        let (a, b) = (g.state().unwrap().pos, c.state().unwrap().pos);
        let worst = a.iter().zip(&b).flat_map(|(x, y)| (0..3).map(move |k| (x[k] - y[k]).abs())).fold(0.0, f32::max);
        println!("after {}: {worst:.2e} m from the CPU", integrator.name());
        // The rollout bound for the substeps so far (2 frames of 16 per integrator).
        assert!(worst < 1e-6 * 16.0 * 2.0 * (k + 1) as f32, "{}: {worst} m", integrator.name());
    }
}
