//! Cones (`core::scene::RodKind::Cone`, `core::contact::cone_contact`): a rod whose base is
//! a disc about `a` and whose apex is `b`, moving and turning like any collider. Analytic
//! cases on every backend (a patch held by Coulomb friction on the slope at the margin
//! from the side, a patch on the base of a cone standing on its apex, that base turning);
//! the kernels and rollouts against the twins are `cylinders.rs`'s, whose scene holds a
//! rod of every kind; refusals there too.

use clothlab_core::scene::ColliderId;
use clothlab_core::{Rod, RodKind, SimParams};
use clothlab_tests::{backend, mean, still_air};

use crate::cylinders::{assert_carried_round, patch_over};

clothlab_tests::per_backend!(a_patch_rests_on_the_slope_and_on_the_base_and_a_turning_base_carries_it_round);

fn a_patch_rests_on_the_slope_and_on_the_base_and_a_turning_base_carries_it_round(name: &str) {
    let margin = SimParams::default().collision_margin;
    // A low cone (base radius 1 m, 0.3 m high: the slope 16.7°, tan 0.3) and Coulomb
    // friction μs = 1, μk = 0.8: a patch dropped half way up the slope stays where it
    // landed, every particle at the margin from the slanted side, to 1e-6 m (a few ulps
    // of 1 m: the contact puts it on the grown side), its centre within 1 mm of where it
    // first touched (it may settle by the patch's sag, never slide).
    let (len, r) = (0.3f32, 1.0f32);
    let low = Rod::new(RodKind::Cone, [0.0, 0.0, 0.0], [0.0, len, 0.0], r);
    let slope = patch_over([0.5, 0.15, 0.0], low, 0.0);
    let coulomb = SimParams { static_friction: 1.0, kinetic_friction: 0.8, ..still_air(0.0) };
    if let Some(mut s) = backend(name, &slope, &coulomb) {
        let slant = (r * r + len * len).sqrt();
        let side = |p: &[f32; 4]| (p[1] * r + (p[0].hypot(p[2]) - r) * len) / slant;
        for _ in 0..5 {
            s.step_frame().unwrap();
        }
        let first = s.state().unwrap();
        for _ in 0..15 {
            s.step_frame().unwrap();
        }
        let st = s.state().unwrap();
        let worst = st.pos.iter().map(|p| (side(p) - margin).abs()).fold(0.0f32, f32::max);
        let centre = |st: &clothlab_core::ClothState| [0, 1, 2].map(|k| mean(st, |i| st.pos[i][k] as f64));
        let (a, b) = (centre(&first), centre(&st));
        let moved = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
        println!("{name:18} on the slope: farthest particle {worst:.2e} m off it, moved {moved:.2e} m");
        assert!(worst <= 1e-6, "{name}: a particle {worst} m off the slope");
        assert!(moved <= 1e-3, "{name}: the patch slid {moved} m down a slope its friction holds");
    }
    // A cone standing on its apex (base up at y = 1, radius 0.3): the base is a flat top;
    // after 0.25 s every particle lies at its height plus the margin, to 1e-6 m.
    let top = Rod::new(RodKind::Cone, [0.0, 1.0, 0.0], [0.0, 0.4, 0.0], 0.3);
    if let Some(mut s) = backend(name, &patch_over([0.1, 1.0, 0.0], top, 0.0), &still_air(0.5)) {
        for _ in 0..15 {
            s.step_frame().unwrap();
        }
        let st = s.state().unwrap();
        let worst = st.pos.iter().map(|p| (p[1] - (1.0 + margin)).abs()).fold(0.0f32, f32::max);
        println!("{name:18} on the base: farthest particle {worst:.2e} m off it");
        assert!(worst <= 1e-6, "{name}: a particle {worst} m off the base");
    }
    // That base turning at ω = 2 rad/s with friction 1 carries the patch round at ω r, as
    // the cylinder's cap does.
    if let Some(mut s) = backend(name, &patch_over([0.1, 1.0, 0.0], top, 2.0), &still_air(1.0)) {
        assert_carried_round(name, s.as_mut(), 2.0, "turning base");
    }
}

#[test]
fn a_cone_scene_file_reads_as_the_rods_it_names_and_draws_its_mesh() {
    // `[[cones]]` beside `[[capsules]]`: the rods in the tables' order (capsules, then
    // cones), each cone's motion on its own index; the picture's mesh holds the cone's
    // triangles (`render::cone_mesh` of 48 steps: 48 side, 48 base).
    let text = "[cloth]\nn = 8\nsize = 1.0\ntop_center = [0, 2, 0]\npinning = \"none\"\n\
        [[cones]]\na = [0, 0, 0]\nb = [0, 1, 0]\nradius = 0.4\n\
        [[cones]]\na = [1, 0, 0]\nb = [1, 0.5, 0]\nradius = 0.2\nmotion = { spin = [0, 1, 0] }\n\
        [[capsules]]\na = [0, 0, 1]\nb = [1, 0, 1]\nradius = 0.1\n";
    let f = clothlab_core::SceneFile::parse(text, "cones.toml").unwrap();
    let kinds: Vec<RodKind> = f.scene.rods.iter().map(|r| r.kind).collect();
    assert_eq!(kinds, [RodKind::Capsule, RodKind::Cone, RodKind::Cone]);
    assert_eq!(f.scene.motions.len(), 1);
    assert_eq!(f.scene.motions[0].0, ColliderId::Rod(RodKind::Cone, 1));
    assert_eq!(f.scene.rod_index(RodKind::Cone, 1), Some(2));
    let (_, idx) = clothlab_core::render::static_mesh(&f.scene);
    let (_, no_cones) = {
        let mut s = f.scene.clone();
        s.rods.retain(|r| r.kind != RodKind::Cone);
        clothlab_core::render::static_mesh(&s)
    };
    assert_eq!(idx.len() - no_cones.len(), 2 * 3 * 96, "two cones of 96 triangles each");
}
