//! Colliders that move (issue 45, `core::motion`), on every backend: analytic cases of a
//! contact's surface velocity, and the GPU recipes against the CPU solver with spheres
//! and boxes moved and spun at every substep.

use clothlab_core::scene::{Aabb, ColliderId, Pinning};
use clothlab_core::{Ease, Integrator, Key, Motion, Repeat, Scene, SimParams, Solver, Sphere};
use clothlab_engine::{RecipeSolver, Variant};
use clothlab_tests::{TABLE_V, assert_checks, backend, mean, moving_table, or_skip, speed, still_air};

/// Sphere radius, m, and its spin about z, rad/s.
const R: f32 = 0.5;
const OMEGA: f32 = 2.0;
/// Frames of 1/60 s (0.25 s: the sphere turns 0.5 rad).
const FRAMES: u32 = 15;

/// A 2 cm patch of 4 × 4 particles lying 1 mm above the top of a sphere that spins about z
/// (its top moves at −x), nothing else in the scene.
fn spinning_sphere() -> Scene {
    let mut s = Scene::with_n(4);
    s.cloth.size = 0.02;
    s.cloth.pinning = Pinning::None;
    let margin = SimParams::default().collision_margin;
    s.cloth.top_center = [0.0, 2.0 * R + margin + 1e-3, -0.01];
    s.floor_y = None;
    s.spheres = vec![Sphere::new([0.0, R, 0.0], R)];
    s.boxes.clear();
    s.motions = vec![(ColliderId::Sphere(0), Motion { spin: [0.0, 0.0, OMEGA], ..Motion::default() })];
    s
}

clothlab_tests::per_backend!(a_patch_on_a_spinning_sphere_moves_with_its_surface_when_it_sticks_and_not_when_it_slides);

fn a_patch_on_a_spinning_sphere_moves_with_its_surface_when_it_sticks_and_not_when_it_slides(name: &str) {
    let margin = SimParams::default().collision_margin;
    // The surface under the patch moves at ω (r + margin): the contacts push the particles
    // to the margin's sphere and leave them the surface's velocity there (friction 1: no
    // tangential velocity relative to it; the normal part into it removed). Read after a
    // frame's last contact, every particle's speed is that of its point of the surface:
    // 1 % covers the patch's extent off the spin's plane (±1 cm: its distance from the
    // axis is 0.9998 of the radius) and the substep's rounding; the patch turns with the
    // sphere as one piece, its springs unstretched.
    let surface = (OMEGA * (R + margin)) as f64;
    if let Some(mut s) = backend(name, &spinning_sphere(), &still_air(1.0)) {
        for _ in 0..FRAMES {
            s.step_frame().unwrap();
        }
        let st = s.state().unwrap();
        let v = speed(&st);
        let vx = mean(&st, |i| st.vel[i][0] as f64);
        println!("{name:18} sticking: mean speed {v:.4} m/s (surface {surface:.4}), mean vx {vx:.4}");
        assert!((v - surface).abs() <= 0.01 * surface, "{name}: sticking patch at {v} m/s, the surface {surface}");
        // Carried over the top towards −x: past 0.4 rad of the 0.5 the sphere turned after
        // the patch landed (it falls its 1 mm in 0.014 s, 0.03 rad of the turn).
        let angle = mean(&st, |i| (-(st.pos[i][0] as f64)).atan2(st.pos[i][1] as f64 - R as f64));
        assert!((0.4..=0.5).contains(&angle), "{name}: the patch turned {angle} rad with the sphere");
    }
    // Friction 0: the contacts take only the normal part of the relative velocity, the
    // spin cannot drag the patch. It stays on the top, sliding off it only as its outer
    // particles (1 cm off the top, 0.02 rad) fall away at g·sin θ ≤ 0.2 m/s²: under
    // 0.05 m/s after 0.25 s, so below 5 % of the sticking speed.
    if let Some(mut s) = backend(name, &spinning_sphere(), &still_air(0.0)) {
        for _ in 0..FRAMES {
            s.step_frame().unwrap();
        }
        let st = s.state().unwrap();
        let v = speed(&st);
        println!("{name:18} sliding: mean speed {v:.4} m/s");
        assert!(v <= 0.05 * surface, "{name}: a frictionless spin moved the patch at {v} m/s");
    }
}

/// Steps `s` 0.5 s (30 frames) on the moving table; the cloth's mean x velocity and how
/// far its centre moved, m.
fn ride(name: &str, s: &mut dyn Solver) -> (f64, f64) {
    let x0 = moving_table(2e-3).cloth.top_center[0] as f64;
    for _ in 0..30 {
        s.step_frame().unwrap();
    }
    assert!((s.time() - 0.5).abs() < 1e-6, "{name}: simulated {} s in 30 frames", s.time());
    let st = s.state().unwrap();
    (mean(&st, |i| st.vel[i][0] as f64), mean(&st, |i| st.pos[i][0] as f64) - x0)
}

clothlab_tests::per_backend!(a_cloth_on_a_table_moving_at_constant_velocity_moves_with_it_when_friction_sticks);

fn a_cloth_on_a_table_moving_at_constant_velocity_moves_with_it_when_friction_sticks(name: &str) {
    // With sticking friction every particle on the table leaves each contact with the
    // table's x velocity exactly (the tangential velocity relative to it is removed, the
    // top's normal is y): the mean vx is 0.5 to rounding (1e-4 relative). The cloth lands
    // within 0.03 s (2 mm and the margin at g), so by t = 0.5 s it has moved 0.5 · (0.5 −
    // 0.03) to 0.25 m.
    let v = TABLE_V as f64;
    if let Some(mut s) = backend(name, &moving_table(2e-3), &still_air(1.0)) {
        let (vx, dx) = ride(name, &mut *s);
        println!("{name:18} on the moving table: vx {vx:.6} m/s, moved {dx:.4} m");
        assert!((vx - v).abs() <= 1e-4 * v, "{name}: the cloth moves at {vx}, the table at {v}");
        assert!((v * 0.47 - 1e-3..=v * 0.5).contains(&dx), "{name}: the cloth moved {dx} m");
    }
}

#[test]
fn every_integrator_takes_the_moving_contacts() {
    // XPBD, the implicit and the Runge-Kutta integrators run the moving table's contacts
    // through the same collide as Verlet (the relative velocity): the cloth rides at the
    // table's speed (1e-4 as above). VBD's contacts are penalty energies with smoothed
    // Coulomb friction on the displacement relative to the table (the paper's: below
    // ε_v the friction is viscous, so a sticking cloth may creep): 1e-3 of the speed
    // (measured on llvmpipe: 0.500000 on the CPU, 0.499999 on each GPU API); it lands later (the penalty lets it sink in first), so
    // it has moved at least 0.5 · (0.5 − 0.05) m. Each on the CPU and on the physics tests'
    // optimized recipe (`OPTIMIZED_ON`), as the physics tests run: each integrator's recipe
    // follows the CPU on every API (integrators.rs; 0.0 m off on llvmpipe), every kernel
    // flavor its twin (api_vs_cpu.rs), and every API's optimized recipe computes the CPU's
    // bits with colliders that move under the cloth (the busy scene below, and friction.rs's
    // moving table with Coulomb's contacts).
    let v = TABLE_V as f64;
    for (integrator, speed_bound, lag) in [
        (Integrator::Xpbd, 1e-4, 0.03),
        (Integrator::Vbd, 1e-3, 0.05),
        (Integrator::Implicit, 1e-4, 0.03),
        (Integrator::Rk4, 1e-4, 0.03),
    ] {
        let params = SimParams { integrator, ..still_air(1.0) };
        let optimized = format!("{} optimized", clothlab_tests::OPTIMIZED_ON.name());
        let keep = |n: &str| n == "cpu" || n == optimized;
        for (name, mut s) in clothlab_tests::backends(&moving_table(2e-3), &params, keep) {
            let (vx, dx) = ride(&name, &mut *s);
            println!("{integrator:?} {name:18} vx {vx:.6} m/s, moved {dx:.4} m");
            assert!((vx - v).abs() <= speed_bound * v, "{integrator:?} on {name}: the cloth moves at {vx}");
            assert!((v * (0.5 - lag) - 1e-3..=v * 0.5).contains(&dx), "{integrator:?} on {name}: moved {dx} m");
        }
    }
}

/// Everything that moves at once, under the cloth from the first substep: a 1 m cloth
/// lying on a sphere that spins about a tilted axis and bobs (keyframed, smooth, looping
/// every 0.2 s), a box sliding into its edge at 1.2 m/s (it reaches it at 0.04 s), the
/// default friction, two strain passes and wind.
fn busy() -> (Scene, SimParams) {
    let mut sc = Scene::with_n(24);
    let margin = SimParams::default().collision_margin;
    sc.cloth.size = 1.0;
    sc.cloth.top_center = [0.0, 1.01 + margin, -0.5];
    sc.cloth.pinning = Pinning::None;
    sc.spheres = vec![Sphere::new([0.0, 0.56, 0.0], 0.45)];
    sc.boxes = vec![Aabb::new([0.55, 0.0, -0.2], [0.85, 1.2, 0.2])];
    let keys = vec![Key::new(0.0, [0.0; 3]), Key::new(0.1, [0.1, 0.05, 0.0]), Key::new(0.2, [0.0; 3])];
    sc.motions = vec![
        (
            ColliderId::Sphere(0),
            Motion { spin: [1.0, 3.0, 0.5], keys, ease: Ease::Smooth, repeat: Repeat::Loop, ..Motion::default() },
        ),
        (ColliderId::Box(0), Motion { velocity: [-1.2, 0.0, 0.0], ..Motion::default() }),
    ];
    (sc, SimParams { strain_iterations: 2, wind: [1.0, 0.0, 0.5], ..SimParams::default() })
}

#[test]
fn the_busy_scenes_colliders_move_the_cloth() {
    // What the rollouts below compare is a cloth the motions move: 12 frames with them
    // and without (the same colliders still) end more than 5 cm apart.
    let (sc, params) = busy();
    let still = Scene { motions: Vec::new(), ..sc.clone() };
    let run = |sc: Scene| {
        let mut s = clothlab_cpu::CpuSolver::new(clothlab_cpu::Exec::Serial, sc, params.clone()).unwrap();
        for _ in 0..12 {
            s.step_frame().unwrap();
        }
        s.state_ref().pos.clone()
    };
    let (a, b) = (run(sc), run(still));
    let moved =
        a.iter().zip(&b).map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).abs()).fold(0.0f32, f32::max)).fold(0.0, f32::max);
    println!("moving vs still colliders: {moved:.3} m apart after 12 frames");
    assert!(moved > 0.05, "the motions moved the cloth only {moved} m");
}

#[test]
fn every_gpu_recipe_and_the_cpu_engine_follow_the_cpu_with_moving_colliders() {
    // The colliders are written before every substep (GpuSolver::record_colliders) from the
    // same host evaluation the CPU solver makes: on llvmpipe the optimized recipes compute
    // the CPU solver's bits (tests/tests/suite/bit_identity.rs), so with motion too: exactly 0;
    // elsewhere within the rollout's bound. 12 frames: the box pushes the cloth's edge, the
    // sphere bobs once under it, spinning. (The naive recipes' atomics add in another order
    // every run: in this scene of sticking contacts that grows chaotically, 8e-5 to 5e-4 m
    // between runs; the analytic tests above run them with motion.)
    let (sc, params) = busy();
    clothlab_tests::assert_rollouts(clothlab_tests::optimized_rollout_solvers(&sc, &params), 12);
}

#[test]
fn motions_a_substep_cannot_resolve_and_temporal_blocking_with_motion_are_refused() {
    // 30 m/s at 16 substeps of 1/60 s moves 0.031 m per substep; a sphere of 0.05 m
    // resolves at most half its radius, 0.025 m: refused in one line naming the motion.
    let mut sc = Scene::with_n(16);
    sc.spheres = vec![Sphere::new([0.0, 0.3, 0.0], 0.05)];
    sc.motions = vec![(ColliderId::Sphere(0), Motion { velocity: [30.0, 0.0, 0.0], ..Motion::default() })];
    let e = clothlab_cpu::CpuSolver::new(clothlab_cpu::Exec::Serial, sc.clone(), SimParams::default())
        .err()
        .expect("too fast for a substep")
        .to_string();
    assert!(e.contains("spheres[0].motion") && e.contains("per substep") && !e.contains('\n'), "{e}");
    // 64 substeps resolve it (0.0078 m per substep)…
    let fine = SimParams { substeps: 64, ..SimParams::default() };
    let mut s = clothlab_cpu::CpuSolver::new(clothlab_cpu::Exec::Serial, sc.clone(), fine).unwrap();
    // …and going back to 16 is refused, the solver keeping its parameters.
    assert!(s.set_params(SimParams::default()).is_err());
    assert_eq!(s.params().substeps, 64);
    // Times that are none.
    assert!(s.set_time(f64::NAN).is_err() && s.set_time(-1.0).is_err() && s.set_time(2.0).is_ok());
    assert_eq!(s.time(), 2.0);
    // Temporal blocking advances substeps with one pose of the colliders: refused, on the
    // CPU engine and on a GPU.
    let (busy_scene, _) = busy();
    let spec = clothlab_engine::VariantSpec::parse("optimized", &["fusion=tile".into(), "temporal=on".into()]).unwrap();
    let o = clothlab_engine::SolverOptions::default();
    let v = spec.resolve(&clothlab_tests::EVERY_CAP, "vulkan").unwrap();
    let e = RecipeSolver::new(clothlab_cpu::Exec::Serial, v, busy_scene.clone(), SimParams::default()).err().unwrap();
    assert!(e.to_string().contains("moving colliders or pins need temporal=off"), "{e}");
    match clothlab_vulkan::vulkan_solver(spec, busy_scene, SimParams::default(), true, o) {
        Ok(_) => panic!("temporal blocking accepted moving colliders"),
        Err(e) => {
            let e = e.to_string();
            if clothlab_tests::gpu_required() || !e.contains("no GPU adapter") {
                assert!(e.contains("moving colliders or pins need temporal=off"), "{e}");
            }
        }
    }
}

#[test]
fn the_kernel_checks_of_a_moving_scene_give_the_kernels_its_colliders_velocities() {
    // `validate --scene` with motion: the kernels run on the colliders at t = 0 with their
    // velocity and spin, as the CPU engine's twins see them (before the fix the GPU's were
    // uploaded still: integrate_collide 0.58 relative off on the spinning sphere). Every
    // kernel of each API's optimized recipe within its bound.
    let (sc, params) = busy();
    assert_checks("moving colliders", &clothlab_tests::optimized_kernel_checks(&sc, &params, 0x5c3));
}

#[test]
fn a_moving_scene_at_many_substeps_steps_on_every_api() {
    // A moving scene writes its colliders before every substep: at 128 substeps a frame
    // those writes (four arrays a substep on Vulkan, each in its own 256-byte slot) pass the
    // 64 KiB of staging a Vulkan frame set aside, refused as a driver error before the
    // staging grew by chunks. Every API steps two frames and stays with the CPU solver.
    let (sc, base) = busy();
    let params = SimParams { substeps: 128, ..base };
    let (v, o) = (Variant::OPTIMIZED, clothlab_engine::SolverOptions::default);
    let mut solvers: Vec<(&str, Box<dyn Solver>)> = Vec::new();
    if let Some(s) = or_skip(clothlab_wgpu::wgpu_solver(v, sc.clone(), params.clone(), o()), "wgpu") {
        solvers.push(("wgpu", Box::new(s)));
    }
    if let Some(s) = or_skip(clothlab_vulkan::vulkan_solver(v, sc.clone(), params.clone(), true, o()), "vulkan") {
        solvers.push(("vulkan", Box::new(s)));
    }
    if let Some(s) = or_skip(clothlab_gl::gl_solver(v, sc.clone(), params.clone(), o()), "gl") {
        solvers.push(("gl", Box::new(s)));
    }
    for (name, mut s) in solvers {
        let c = clothlab_cpu::validate::validate_rollout(&mut *s, 2).unwrap_or_else(|e| panic!("{name}: {e}"));
        println!("{name:8} {} max {:.2e} (bound {:.0e})", c.what, c.max_abs, c.bound);
        assert!(c.error <= c.bound, "{name}: {:.2e} over {:.0e}", c.error, c.bound);
    }
}
