//! Self-collision on the CPU: the fast solvers (serial and rayon) compute the bits of the
//! recipe the GPU backends run (the CPU engine executing the twins, kernel by kernel).

use clothlab_core::{Integrator, SceneFile, Solver};
use clothlab_cpu::{CpuSolver, Exec};
use clothlab_engine::{RecipeSolver, Variant};

fn bits(v: &[[f32; 4]]) -> Vec<[u32; 4]> {
    v.iter().map(|p| p.map(f32::to_bits)).collect()
}

#[test]
fn the_fast_cpu_solvers_compute_the_bits_of_the_self_collision_recipe() {
    // The heap scene at n = 24: its lower edge lands at frame 14 and the cloth folds onto
    // itself; 40 frames, Verlet and XPBD.
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/heap.toml");
    let f = SceneFile::load(&path).unwrap();
    assert!(f.params.self_collision.particles());
    let mut scene = f.scene.clone();
    scene.cloth.n = 24;
    for integrator in [Integrator::Verlet, Integrator::Xpbd] {
        let params = clothlab_core::SimParams { integrator, ..f.params.clone() };
        let mut engine = RecipeSolver::new(Exec::Serial, Variant::OPTIMIZED, scene.clone(), params.clone()).unwrap();
        let mut serial = CpuSolver::new(Exec::Serial, scene.clone(), params.clone()).unwrap();
        let mut rayon = CpuSolver::new(Exec::Parallel, scene.clone(), params.clone()).unwrap();
        let off = clothlab_core::SimParams { self_collision: clothlab_core::SelfCollision::Off, ..params.clone() };
        let mut without = CpuSolver::new(Exec::Serial, scene.clone(), off).unwrap();
        for frame in 0..40 {
            engine.step_frame().unwrap();
            serial.step_frame().unwrap();
            rayon.step_frame().unwrap();
            without.step_frame().unwrap();
            let e = engine.state().unwrap();
            for s in [&serial, &rayon] {
                let st = s.state_ref();
                assert!(bits(&e.pos) == bits(&st.pos), "{integrator:?} frame {frame}: {} pos", s.name());
                assert!(bits(&e.vel) == bits(&st.vel), "{integrator:?} frame {frame}: {} vel", s.name());
            }
        }
        // And it did something: the cloth lies otherwise than without self-collision.
        let moved = serial
            .state_ref()
            .pos
            .iter()
            .zip(&without.state_ref().pos)
            .map(|(a, b)| (a[1] - b[1]).abs())
            .fold(0.0f32, f32::max);
        println!("{integrator:?}: largest difference from the run without self-collision {moved:.4} m");
        assert!(moved > 1e-3, "{integrator:?}: self-collision changed nothing ({moved} m)");
    }
}

#[test]
fn the_kernel_check_of_the_response_starts_from_many_contacts() {
    // What `validate` and the GPU tests compare self_collide on: particles put within the
    // thickness of far ones (kernels::built_hash), so that the response has work to do.
    use clothlab_engine::kernels::SELF_COLLIDE;
    use clothlab_engine::recipe::run;
    use clothlab_engine::validate::KernelInput;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/heap.toml");
    let f = SceneFile::load(&path).unwrap();
    let input = KernelInput::for_scene(&f.scene, 3, &f.params).unwrap();
    let k = SELF_COLLIDE.plain();
    let mut b = input.for_kernel(k);
    let before = b.pos.clone();
    input.engine.run(&run(k), &input.p, 0, &mut b);
    // After the swap, pos is the response's output.
    let moved = b.pos.iter().zip(&before).filter(|(a, c)| a != c).count();
    let np = before.len();
    println!("{moved} of {np} particles pushed apart");
    assert!(moved >= np / 10, "only {moved} of {np} particles moved");
}
