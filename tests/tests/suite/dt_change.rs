//! A changed time step keeps the cloth's velocity (issue 16), on every backend: the state
//! holds the velocities themselves (issue 31), so `frame_dt` or `substeps` changing leaves
//! them as they are. (When the state was Verlet's history it had to be rescaled: without
//! that, halving dt doubled the apparent velocity `(x − x*) / dt` at once.)

use clothlab_core::{Scene, SimParams, Solver};
use clothlab_cpu::{CpuSolver, Exec};
use clothlab_engine::{RecipeSolver, Variant};
use clothlab_tests::Api;

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
    let speed = before.vel.iter().flatten().fold(0.0f32, |m, x| m.max(x.abs()));
    assert!(speed > 0.1, "{name}: the cloth should be moving after 6 frames ({speed} m/s)");
    // Exactly: nothing is recomputed from positions.
    assert!(before.vel == after.vel, "{name}: the velocities changed with dt (speed {speed} m/s)");
    assert!(before.pos == after.pos, "{name}: positions must not move");
}

#[test]
fn a_new_time_step_keeps_the_velocity_on_the_cpu_solvers_and_engine() {
    let scene = Scene::with_n(24);
    let p = SimParams::default();
    check(&mut CpuSolver::new(Exec::Serial, scene.clone(), p.clone()).unwrap());
    check(&mut CpuSolver::new(Exec::Parallel, scene.clone(), p.clone()).unwrap());
    check(&mut RecipeSolver::new(Exec::Serial, Variant::NAIVE, scene, p).unwrap());
}

clothlab_tests::per_api!(a_new_time_step_keeps_the_velocity);

/// The API's naive recipe on Vulkan (under the validation layer), its optimized one on
/// wgpu and GL.
fn a_new_time_step_keeps_the_velocity(api: Api) {
    let variant = if api == Api::Vulkan { Variant::NAIVE } else { Variant::OPTIMIZED };
    if let Some(s) = api.solver(variant, &Scene::with_n(24), &SimParams::default()) {
        check(&mut *s.into_solver());
    }
}
