//! A changed time step keeps the cloth's velocity (issue 16): Verlet's history is rescaled
//! when `frame_dt` or `substeps` change, on every backend. Without it, halving dt doubles
//! the apparent velocity `(x − x*) / dt` at once.

use clothlab_core::{CpuSolver, Exec, Scene, SimParams, Solver};
use clothlab_engine::{RecipeSolver, SolverOptions, Variant};
use clothlab_tests::or_skip;
use clothlab_vulkan::vulkan_solver;
use clothlab_wgpu::wgpu_solver;

fn check(solver: &mut dyn Solver) {
    let name = solver.name().to_owned();
    for _ in 0..6 {
        solver.step_frame().unwrap();
    }
    let before = solver.state().unwrap();
    let old = solver.params().clone();
    let new = SimParams { substeps: old.substeps * 2, ..old.clone() };
    solver.set_params(new.clone()).unwrap();
    let after = solver.state().unwrap();
    let v = |s: &clothlab_core::ClothState, dt: f32| -> Vec<[f32; 3]> {
        s.pos.iter().zip(&s.prev).map(|(x, p)| [0, 1, 2].map(|c| (x[c] - p[c]) / dt)).collect()
    };
    let (va, vb) = (v(&before, old.dt()), v(&after, new.dt()));
    let speed = va.iter().flatten().fold(0.0f32, |m, x| m.max(x.abs()));
    assert!(speed > 0.1, "{name}: the cloth should be moving after 6 frames ({speed} m/s)");
    let worst = va.iter().zip(&vb).flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs())).fold(0.0, f32::max);
    // Rounding of x* = x − (x − x*)·r: a few ulps of coordinates up to ~2 m, over the new dt.
    let bound = 4.0 * f32::EPSILON * 2.0 / new.dt();
    assert!(worst <= bound, "{name}: velocity changed by {worst} m/s with dt (bound {bound}, speed {speed})");
    assert!(before.pos == after.pos, "{name}: positions must not move");
}

#[test]
fn a_new_time_step_keeps_the_velocity_on_every_backend() {
    let scene = Scene::with_n(24);
    let p = SimParams::default();
    check(&mut CpuSolver::new(Exec::Serial, scene.clone(), p.clone()).unwrap());
    check(&mut CpuSolver::new(Exec::Parallel, scene.clone(), p.clone()).unwrap());
    check(&mut RecipeSolver::new(Exec::Serial, Variant::NAIVE, scene.clone(), p.clone()).unwrap());
    if let Some(mut g) =
        or_skip(wgpu_solver(Variant::OPTIMIZED, scene.clone(), p.clone(), SolverOptions::default()), "wgpu")
    {
        check(&mut g);
    }
    if let Some(mut v) = or_skip(vulkan_solver(Variant::NAIVE, scene, p, true, SolverOptions::default()), "vulkan") {
        check(&mut v);
    }
}
