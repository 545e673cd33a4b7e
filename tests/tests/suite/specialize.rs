//! `specialize=on` (`core::layout::Uses`, `engine::variant::Specialize`): kernels compiled
//! for the scene. Every scene's bits are held by the scene files' test (the optimized
//! preset specialises); here, what a specialised solver must do when the scene's uses
//! change under it, and that a specialised kernel keeps only what the scene uses.

use clothlab_core::layout::Uses;
use clothlab_core::scene::Pinning;
use clothlab_core::{Scene, SimParams};
use clothlab_engine::kernels as k;
use clothlab_tests::{backends, still_air};

/// A 0.2 m cloth of 8 × 8 lying on the floor at the margin, sliding at 1 m/s along x.
fn sliding() -> Scene {
    let mut sc = Scene::with_n(8);
    sc.cloth.size = 0.2;
    sc.cloth.pinning = Pinning::None;
    sc.cloth.top_center = [0.0, SimParams::default().collision_margin, -0.1];
    sc.cloth.velocity = [1.0, 0.0, 0.0];
    sc.spheres.clear();
    sc
}

#[test]
fn a_specialised_solver_rebuilds_its_kernels_when_coulomb_is_turned_on() {
    // Started without friction (Coulomb's code dropped from the kernels), then, after 2
    // frames, Coulomb's coefficients set (as the app's panel does, live): each API's
    // optimized recipe (specialised) must follow the CPU solver stepped the same way to
    // the bit (the optimized recipes compute the CPU's bits on llvmpipe), and the cloth
    // slows at μk g: 1 − 0.3 · 9.81 · 4/60 = 0.80 m/s after 4 frames, within 0.02 (the
    // first substeps' contact). Kept without Coulomb's code, it would slide on at 1 m/s.
    let share = still_air(0.0);
    let coulomb = SimParams { static_friction: 0.5, kinetic_friction: 0.3, ..share.clone() };
    assert!(!Uses::of(&sliding(), &share).coulomb && Uses::of(&sliding(), &coulomb).coulomb);
    let mut runs = backends(&sliding(), &share, |n| n == "cpu" || n.ends_with("optimized"));
    assert!(runs.len() >= 2, "no GPU recipe to compare");
    let mut states = Vec::new();
    for (name, s) in &mut runs {
        for _ in 0..2 {
            s.step_frame().unwrap();
        }
        s.set_params(coulomb.clone()).unwrap();
        for _ in 0..4 {
            s.step_frame().unwrap();
        }
        let st = s.state().unwrap();
        let vx = st.vel.iter().map(|v| v[0]).sum::<f32>() / st.vel.len() as f32;
        println!("{name:18} mean vx after Coulomb for 4 frames: {vx:.5} m/s");
        assert!((vx - 0.804).abs() < 0.02, "{name}: {vx} m/s, not slowed at μk g");
        states.push((name.clone(), st));
    }
    let (_, cpu) = &states[0];
    for (name, st) in &states[1..] {
        assert_eq!(st.pos, cpu.pos, "{name}: positions differ from the CPU's");
        assert_eq!(st.vel, cpu.vel, "{name}: velocities differ from the CPU's");
    }
}

#[test]
fn a_specialised_kernel_says_what_the_scene_uses_and_compiles_on_every_path() {
    // The default scene (three still spheres, the floor, the share's friction) uses none
    // of the four: its kernels' WGSL carries the four constants false, and naga compiles
    // it to SPIR-V and GLSL (what Vulkan and GL build; wgpu takes the WGSL).
    let uses = Uses::of(&Scene::default(), &SimParams::default());
    assert_eq!(uses, Uses { rods: false, bodies: false, coulomb: false, motion: false });
    for def in [&k::INTEGRATE_COLLIDE, &k::COLLIDE, &k::VBD_COLOUR] {
        let general = def.plain();
        let special = general.with_uses(uses);
        let wgsl = special.wgsl().unwrap();
        assert!(wgsl.contains("const USES_RODS: bool = false;") && wgsl.contains("const USES_MOTION: bool = false;"));
        assert!(general.wgsl().unwrap().contains("const USES_RODS: bool = true;"));
        assert_ne!(special, general, "a specialised kernel is another pipeline");
        // A validation offers both: its rows name them apart.
        assert_eq!(general.report_name(), general.shader_name());
        assert_eq!(special.report_name(), format!("{}[uses: none]", general.shader_name()));
        assert!(!special.spirv().unwrap().is_empty(), "{special}: no SPIR-V");
        assert!(special.glsl().unwrap().text.contains("void main"), "{special}: no GLSL");
    }
}
