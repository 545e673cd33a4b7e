//! Cylinders (`core::scene::RodKind::Cylinder`, `core::contact::cylinder_contact`): a
//! capped cylinder, moving and turning like any collider. Analytic cases on every backend
//! (a patch at rest on the cap and on the side, a turntable), the GPU recipes and kernels
//! against the CPU twins with a rod of every kind, refusals of every kind's table.

use clothlab_core::scene::{ColliderId, Pinning};
use clothlab_core::{Integrator, Motion, Rod, RodKind, Scene, SceneFile, SimParams};
use clothlab_tests::{assert_checks, backend, mean, still_air};

/// A 2 cm patch of 4 × 4 particles with its centre 1 mm plus the margin above the point
/// `at`, over the rod `rod` alone (no floor, no sphere) spinning at `spin` rad/s about the
/// vertical: `cones.rs` drops it on cones too.
pub(super) fn patch_over(at: [f32; 3], rod: Rod, spin: f32) -> Scene {
    let mut s = Scene::with_n(4);
    s.cloth.size = 0.02;
    s.cloth.pinning = Pinning::None;
    let margin = SimParams::default().collision_margin;
    s.cloth.top_center = [at[0], at[1] + margin + 1e-3, at[2] - 0.01];
    s.floor_y = None;
    s.spheres.clear();
    s.rods = vec![rod];
    s.motions = vec![(ColliderId::Rod(rod.kind, 0), Motion { spin: [0.0, spin, 0.0], ..Motion::default() })];
    s
}

/// The patch of [`patch_over`] `off` m from the axis of an upright cylinder of radius
/// 0.3 m whose top cap is at y = 1, the cylinder turning at `spin` rad/s.
fn turntable(off: f32, spin: f32) -> Scene {
    patch_over([off, 1.0, 0.0], Rod::new(RodKind::Cylinder, [0.0, 0.6, 0.0], [0.0, 1.0, 0.0], 0.3), spin)
}

/// After 30 frames on a face turning at `omega` rad/s about the vertical with friction 1,
/// each particle has left each contact at the face's velocity there, ω times its
/// distance from the axis: the patch's mean speed is ω times its mean distance within
/// 0.5 % (the last substep's gravity and rounding; measured to 4 digits), and it has
/// turned about the axis (its centre's angle from +x by more than 0.5 rad in 0.5 s: ω t =
/// 1 rad less the first contacts). `what` names the face.
pub(super) fn assert_carried_round(name: &str, s: &mut dyn clothlab_core::Solver, omega: f64, what: &str) {
    for _ in 0..30 {
        s.step_frame().unwrap();
    }
    let st = s.state().unwrap();
    let r = |i: usize| (st.pos[i][0] as f64).hypot(st.pos[i][2] as f64);
    let v = mean(&st, |i| st.vel[i][..3].iter().map(|&c| (c as f64).powi(2)).sum::<f64>().sqrt());
    let expect = omega * mean(&st, r);
    let (x, z) = (mean(&st, |i| st.pos[i][0] as f64), mean(&st, |i| st.pos[i][2] as f64));
    let turned = (-z).atan2(x);
    println!("{name:18} {what}: mean speed {v:.4} m/s (ω r̄ {expect:.4}), turned {turned:.3} rad");
    assert!((v - expect).abs() <= 0.005 * expect, "{name}: {v} m/s, the {what} {expect}");
    assert!(turned > 0.5, "{name}: turned {turned} rad");
}

clothlab_tests::per_backend!(a_patch_rests_on_the_cap_and_the_side_and_a_turntable_carries_it_round);

fn a_patch_rests_on_the_cap_and_the_side_and_a_turntable_carries_it_round(name: &str) {
    let margin = SimParams::default().collision_margin;
    // On the cap: after 0.25 s every particle lies at the cap's height plus the margin,
    // to 1e-6 m (a few ulps of 1 m: the contact puts it there exactly).
    if let Some(mut s) = backend(name, &turntable(0.1, 0.0), &still_air(0.5)) {
        for _ in 0..15 {
            s.step_frame().unwrap();
        }
        let st = s.state().unwrap();
        let worst = st.pos.iter().map(|p| (p[1] - (1.0 + margin)).abs()).fold(0.0f32, f32::max);
        println!("{name:18} on the cap: farthest particle {worst:.2e} m off it");
        assert!(worst <= 1e-6, "{name}: a particle {worst} m off the cap");
    }
    // On the side of a lying cylinder (axis along x): every particle at the radius plus
    // the margin from the axis, to 1e-6 m, as on a capsule's tube.
    let mut side = turntable(0.0, 0.0);
    side.rods = vec![Rod::new(RodKind::Cylinder, [-0.5, 1.0, 0.0], [0.5, 1.0, 0.0], 0.2)];
    side.cloth.top_center = [0.0, 1.2 + margin + 1e-3, -0.01];
    side.motions.clear();
    if let Some(mut s) = backend(name, &side, &still_air(0.5)) {
        for _ in 0..15 {
            s.step_frame().unwrap();
        }
        let st = s.state().unwrap();
        let off = |p: &[f32; 4]| (((p[1] - 1.0).powi(2) + p[2].powi(2)).sqrt() - (0.2 + margin)).abs();
        let worst = st.pos.iter().map(off).fold(0.0f32, f32::max);
        println!("{name:18} on the side: farthest particle {worst:.2e} m off it");
        assert!(worst <= 1e-6, "{name}: a particle {worst} m off the side");
    }
    // A turntable at ω = 2 rad/s with friction 1 carries the patch round at ω r.
    if let Some(mut s) = backend(name, &turntable(0.1, 2.0), &still_air(1.0)) {
        assert_carried_round(name, s.as_mut(), 2.0, "turntable");
    }
}

#[test]
fn every_gpu_recipe_and_kernel_follows_the_cpu_with_moving_turning_rods_of_every_kind() {
    // A drum that turns, slides and bobs (keys) under a falling cloth, a still post
    // beside it, a capsule before them and a spinning cone whose apex the cloth meets
    // (the rods' table holds every kind): the optimized recipes give the CPU's bits
    // (0 m over 12 frames); the kernel checks — collide, and VBD's colour sweep with its
    // contact energies — sink particles into every collider.
    let mut sc = Scene::with_n(24);
    sc.cloth.size = 1.2;
    sc.cloth.pinning = Pinning::None;
    sc.cloth.top_center = [0.0, 1.0, -0.6];
    sc.spheres.clear();
    sc.rods = vec![
        Rod::new(RodKind::Capsule, [-0.6, 0.5, 0.4], [0.6, 0.5, 0.4], 0.05),
        Rod::new(RodKind::Cylinder, [-0.6, 0.75, 0.1], [0.6, 0.75, 0.1], 0.12),
        Rod::new(RodKind::Cylinder, [0.0, 0.0, -0.3], [0.0, 0.7, -0.3], 0.08),
        Rod::new(RodKind::Cone, [0.35, 0.3, -0.1], [0.35, 0.9, -0.1], 0.15),
    ];
    let keys = vec![
        clothlab_core::Key::new(0.0, [0.0; 3]),
        clothlab_core::Key { rotate_deg: [0.0, 30.0, 20.0], ..clothlab_core::Key::new(0.2, [0.1, 0.05, 0.0]) },
    ];
    sc.motions = vec![
        (ColliderId::Rod(RodKind::Cylinder, 0), Motion { keys, ..Motion::default() }),
        (ColliderId::Rod(RodKind::Cone, 0), Motion { spin: [0.0, 3.0, 0.0], ..Motion::default() }),
    ];
    let params = SimParams::default();
    let checks = clothlab_tests::optimized_kernel_checks(&sc, &params, 0xc7);
    assert!(checks.iter().any(|c| c.what.contains("collide")), "no check of a collide kernel");
    assert_checks("cylinders", &checks);
    let vbd = SimParams { integrator: Integrator::Vbd, ..params.clone() };
    let checks = clothlab_tests::optimized_kernel_checks(&sc, &vbd, 0xc8);
    assert!(checks.iter().any(|c| c.what.contains("vbd_colour")), "no check of VBD's sweep");
    assert_checks("cyl. vbd", &checks);
    clothlab_tests::assert_rollouts(clothlab_tests::optimized_rollout_solvers(&sc, &params), 12);
}

#[test]
fn bad_cylinders_and_cones_are_refused_in_one_line() {
    let file = |cyl: &str| format!("[cloth]\nn = 8\nsize = 1.0\ntop_center = [0, 2, 0]\npinning = \"none\"\n{cyl}");
    let cases = [
        ("[[cylinders]]\na = [0, 0, 0]\nb = [1, 0, 0]\nradius = -1\n", "cylinders[0].radius", None),
        ("[[cylinders]]\na = [0, 0, 0]\nb = [0, 0, 0]\nradius = 0.1\n", "cylinders[0].b", None),
        ("[[cylinders]]\na = [0, 0, inf]\nb = [1, 0, 0]\nradius = 0.1\n", "cylinders[0].a", None),
        ("[[cylinders]]\na = [0, 0, 0]\nb = [1, 0, 0]\n", "missing field `radius`", Some(6)),
        ("[[cylinders]]\na = [0, 0, 0]\nb = [1, 0, 0]\nradius = 0.1\nheight = 2\n", "unknown field", Some(10)),
        (
            "[[cylinders]]\na = [0, 0, 0]\nb = [1, 0, 0]\nradius = 0.1\nmotion = { spin = [0, 900, 0] }\n",
            "cylinders[0]",
            None,
        ),
        // A cone's ends must lie apart too, and its index is its own table's.
        ("[[cones]]\na = [0, 0, 0]\nb = [0, 0, 0]\nradius = 0.1\n", "cones[0].b", None),
        (
            "[[cylinders]]\na = [0, 0, 0]\nb = [1, 0, 0]\nradius = 0.1\n[[cones]]\na = [0, 0, 0]\nb = [0, 1, 0]\nradius = 0\n",
            "cones[0].radius",
            None,
        ),
        ("[[cones]]\na = [0, 0, 0]\nb = [0, 1, 0]\nradius = 0.1\napex = 2\n", "unknown field", Some(10)),
    ];
    for (cyl, expect, line) in cases {
        let e = SceneFile::parse(&file(cyl), "bad.toml").expect_err(expect);
        let msg = e.to_string();
        println!("{msg}");
        assert!(msg.contains(expect) && !msg.contains('\n'), "{expect}: {msg}");
        if let Some(l) = line {
            assert_eq!(e.at.map(|a| a.0), Some(l), "{msg}");
        }
    }
    // Every kind shares the rods' table of 16.
    let mut s = turntable(0.0, 0.0);
    s.rods = vec![s.rods[0]; 9];
    s.rods.extend([Rod::new(RodKind::Capsule, [0.0; 3], [1.0, 0.0, 0.0], 0.1); 8]);
    let e = s.validate().unwrap_err().to_string();
    assert!(e.contains("at most 16 rods (capsules, cylinders, cones) together"), "{e}");
}
