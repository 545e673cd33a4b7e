//! Capsules (`core::scene::RodKind::Capsule`): the points within a radius of a segment,
//! moving and turning like any collider. Analytic cases on every backend, the degenerate
//! capsule against the sphere, the GPU recipes against the CPU twins, refusals.

use clothlab_core::scene::{ColliderId, Pinning};
use clothlab_core::{ClothState, Motion, Rod, RodKind, Scene, SceneFile, SimParams, Sphere};
use clothlab_tests::{assert_checks, backend, mean, still_air};

/// Radius of the roller, m, and its spin about its own axis (x), rad/s.
const R: f32 = 0.2;
const OMEGA: f32 = 2.0;

/// A 2 cm patch 1 mm above the top of a horizontal capsule along x (its axis at y = 1),
/// `spin` about the axis.
fn roller(spin: f32) -> Scene {
    let mut s = Scene::with_n(4);
    s.cloth.size = 0.02;
    s.cloth.pinning = Pinning::None;
    let margin = SimParams::default().collision_margin;
    s.cloth.top_center = [0.0, 1.0 + R + margin + 1e-3, -0.01];
    s.floor_y = None;
    s.spheres.clear();
    s.rods = vec![Rod::new(RodKind::Capsule, [-0.5, 1.0, 0.0], [0.5, 1.0, 0.0], R)];
    s.motions = vec![(ColliderId::Rod(RodKind::Capsule, 0), Motion { spin: [spin, 0.0, 0.0], ..Motion::default() })];
    s
}

clothlab_tests::per_backend!(a_patch_rests_on_a_capsule_and_a_roller_carries_it_when_it_sticks);

fn a_patch_rests_on_a_capsule_and_a_roller_carries_it_when_it_sticks(name: &str) {
    let margin = SimParams::default().collision_margin;
    // Still: after 0.25 s the patch lies on the top of the tube, every particle at the
    // radius plus the margin from the axis (the contact puts it there; the patch's ±1 cm
    // across the tube puts its corners lower on the curve, at the same distance): to
    // 1e-6 m, a few ulps of 1.2 m (measured 3e-8).
    if let Some(mut s) = backend(name, &roller(0.0), &still_air(0.5)) {
        for _ in 0..15 {
            s.step_frame().unwrap();
        }
        let st = s.state().unwrap();
        let worst = st
            .pos
            .iter()
            .map(|p| (((p[1] - 1.0).powi(2) + p[2].powi(2)).sqrt() - (R + margin)).abs())
            .fold(0.0f32, f32::max);
        println!("{name:18} still: farthest particle {worst:.2e} m off the tube");
        assert!(worst <= 1e-6, "{name}: a particle {worst} m off the tube's margin");
    }
    // Turning about its axis at ω with friction 1: the patch leaves each contact at the
    // surface's velocity, speed ω (r + margin) within 0.2 % (every particle sits at r +
    // margin from the axis, so its surface point moves at exactly that speed; the bound
    // is rounding and the last substep's gravity; measured to 4 digits), and it has been
    // carried round towards +z (ω along +x turns the top, +y, towards +z).
    let surface = (OMEGA * (R + margin)) as f64;
    if let Some(mut s) = backend(name, &roller(OMEGA), &still_air(1.0)) {
        for _ in 0..15 {
            s.step_frame().unwrap();
        }
        let st = s.state().unwrap();
        let v = mean(&st, |i| st.vel[i][..3].iter().map(|&c| (c as f64).powi(2)).sum::<f64>().sqrt());
        let z = mean(&st, |i| st.pos[i][2] as f64);
        println!("{name:18} rolling: mean speed {v:.4} m/s (surface {surface:.4}), carried to z = {z:.3}");
        assert!((v - surface).abs() <= 0.002 * surface, "{name}: {v} m/s, the surface {surface}");
        assert!(z > 0.05, "{name}: not carried round (z {z})");
    }
}

#[test]
fn a_capsule_of_no_length_is_the_sphere_to_the_bit() {
    // Its axis a point: the nearest axis point is `a + 0·ab = a`, and the contact is the
    // sphere's, operation for operation. The default scene with its three spheres as such
    // capsules rolls out as the spheres do, on the CPU solvers and the optimized recipes.
    let params = SimParams::default();
    let mut spheres = Scene::with_n(24);
    spheres.cloth.size = 1.6;
    let mut capsules = spheres.clone();
    capsules.rods =
        spheres.spheres.iter().map(|s: &Sphere| Rod::new(RodKind::Capsule, s.center, s.center, s.radius)).collect();
    capsules.spheres.clear();
    let run = |scene: &Scene, keep: &str| -> Vec<(String, ClothState)> {
        clothlab_tests::backends(scene, &params, |n| n.contains(keep))
            .into_iter()
            .map(|(name, mut s)| {
                for _ in 0..40 {
                    s.step_frame().unwrap();
                }
                (name, s.state().unwrap())
            })
            .collect()
    };
    for keep in ["cpu", "optimized"] {
        for ((name, a), (_, b)) in run(&spheres, keep).into_iter().zip(run(&capsules, keep)) {
            let worst = a
                .pos
                .iter()
                .zip(&b.pos)
                .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
                .fold(0.0, f32::max);
            println!("{name:18} capsules against spheres: {worst:.1e} m");
            assert_eq!(worst, 0.0, "{name}: point capsules {worst} m from the spheres");
        }
    }
}

#[test]
fn every_gpu_recipe_and_the_cpu_engine_follow_the_cpu_with_a_moving_capsule() {
    // A roller that turns, slides and bobs (keys) under a falling cloth, a still bar
    // beside it: the optimized recipes give the CPU's bits (0 m over 12 frames); the
    // kernel checks sink particles into both capsules.
    let mut sc = Scene::with_n(24);
    sc.cloth.size = 1.2;
    sc.cloth.pinning = Pinning::None;
    sc.cloth.top_center = [0.0, 1.0, -0.6];
    sc.spheres.clear();
    sc.rods = vec![
        Rod::new(RodKind::Capsule, [-0.6, 0.75, 0.1], [0.6, 0.75, 0.1], 0.1),
        Rod::new(RodKind::Capsule, [-0.6, 0.6, -0.3], [0.6, 0.7, -0.3], 0.05),
    ];
    let keys = vec![
        clothlab_core::Key::new(0.0, [0.0; 3]),
        clothlab_core::Key { rotate_deg: [0.0, 30.0, 0.0], ..clothlab_core::Key::new(0.2, [0.1, 0.05, 0.0]) },
    ];
    sc.motions = vec![(ColliderId::Rod(RodKind::Capsule, 0), Motion { keys, ..Motion::default() })];
    let params = SimParams::default();
    let checks = clothlab_tests::optimized_kernel_checks(&sc, &params, 0xc4);
    assert!(checks.iter().any(|c| c.what.contains("collide")), "no check of a collide kernel");
    assert_checks("capsules", &checks);
    clothlab_tests::assert_rollouts(clothlab_tests::optimized_rollout_solvers(&sc, &params), 12);
}

#[test]
fn bad_capsules_are_refused_in_one_line() {
    let file = |caps: &str| format!("[cloth]\nn = 8\nsize = 1.0\ntop_center = [0, 2, 0]\npinning = \"none\"\n{caps}");
    let cases = [
        ("[[capsules]]\na = [0, 0, 0]\nb = [1, 0, 0]\nradius = -1\n", "capsules[0].radius", None),
        ("[[capsules]]\na = [0, nan, 0]\nb = [1, 0, 0]\nradius = 0.1\n", "capsules[0].a", None),
        ("[[capsules]]\na = [0, 0, 0]\nb = [1, 0, 0]\n", "missing field `radius`", Some(6)),
        ("[[capsules]]\na = [0, 0, 0]\nb = [1, 0, 0]\nradius = 0.1\nlength = 2\n", "unknown field", Some(10)),
        (
            "[[capsules]]\na = [0, 0, 0]\nb = [1, 0, 0]\nradius = 0.1\nmotion = { spin = [0, 1, 0], keys = [{ t = 0, offset = [0, 0, 0] }, { t = 1, offset = [0, 0, 0], rotate_deg = [0, 9, 0] }] }\n",
            "not both",
            None,
        ),
    ];
    for (caps, expect, line) in cases {
        let e = SceneFile::parse(&file(caps), "bad.toml").expect_err(expect);
        let msg = e.to_string();
        println!("{msg}");
        assert!(msg.contains(expect) && !msg.contains('\n'), "{expect}: {msg}");
        if let Some(l) = line {
            assert_eq!(e.at.map(|a| a.0), Some(l), "{msg}");
        }
    }
    let mut s = roller(0.0);
    s.rods = vec![s.rods[0]; 17];
    let e = s.validate().unwrap_err().to_string();
    assert!(e.contains("capsules") && e.contains("at most 16"), "{e}");
}
