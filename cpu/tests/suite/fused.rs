//! The fused Verlet sweep (core/src/cpu/fused.rs) against the kernel-by-kernel step,
//! which tests/physics.rs pins to the twins: bit for bit, at every vector width this CPU
//! has, serial and in bands, through every case the sweep handles apart (grid edges, the
//! floor, spheres, a box, the grab, wind, tethers, 0 to 3 strain passes, widths that do
//! not divide the row).

use clothlab_core::grid::V4;
use clothlab_core::{Aabb, Grab, Pinning, Scene, SimParams, Solver};
use clothlab_cpu::{CpuSolver, Exec, Simd};

/// The first particle whose bits differ, with both values; `None` when all agree.
fn first_difference(want: &[V4], got: &[V4]) -> Option<String> {
    let k = want.iter().zip(got).position(|(a, b)| a.map(f32::to_bits) != b.map(f32::to_bits))?;
    Some(format!("particle {k} of {}: want {:?}, got {:?}", want.len(), want[k], got[k]))
}

/// Runs `frames` frames kernel by kernel and fused (every width, both executions) from
/// the same start and compares every buffer of the state after each frame.
fn compare(scene: &Scene, params: &SimParams, frames: u32, grab: Option<Grab>) {
    let n = scene.cloth.n;
    let mut reference = CpuSolver::new(Exec::Serial, scene.clone(), params.clone()).unwrap();
    reference.fused = false;
    reference.set_grab(grab);
    let mut runs = Vec::new();
    for simd in Simd::ALL.into_iter().filter(|s| s.available()) {
        for exec in [Exec::Serial, Exec::Parallel] {
            let mut s = CpuSolver::new(exec, scene.clone(), params.clone()).unwrap();
            s.set_simd(simd).unwrap();
            s.set_grab(grab);
            assert!(s.runs_fused(), "n = {n}: the sweep should take this scene");
            runs.push((format!("{simd}, {exec:?}"), s));
        }
    }
    let mut gap = f32::INFINITY;
    for f in 0..frames {
        reference.step_frame().unwrap();
        let want = reference.state().unwrap();
        gap = gap.min(closest_gap(scene, &want));
        for (name, s) in &mut runs {
            s.step_frame().unwrap();
            let got = s.state().unwrap();
            let at = format!("n = {n}, {} strain passes, frame {f}, {name}", params.strain_iterations);
            for (what, w, g) in [
                ("positions", &want.pos, &got.pos),
                ("velocities", &want.vel, &got.vel),
                ("normals", &want.normal, &got.normal),
                ("wind force", &want.force, &got.force),
            ] {
                assert_eq!(first_difference(w, g), None, "{at}: {what}");
            }
        }
    }
    // And the run went through contacts: in some frame a particle came within 2 cm (twice
    // the collision margin) of the floor, a sphere or the box.
    assert!(gap < 0.02, "n = {n}: nothing came near a collider (closest {gap} m)");
}

/// The smallest distance of a particle of `st` to the floor, a sphere or a box.
fn closest_gap(scene: &Scene, st: &clothlab_core::grid::ClothState) -> f32 {
    st.pos
        .iter()
        .map(|p| {
            let spheres = scene.spheres.iter().map(|s| {
                let d: f32 = (0..3).map(|k| (p[k] - s.center[k]).powi(2)).sum();
                d.sqrt() - s.radius
            });
            let boxes = scene.boxes.iter().map(|b| {
                let d: f32 = (0..3).map(|k| (b.min[k] - p[k]).max(p[k] - b.max[k]).max(0.0).powi(2)).sum();
                d.sqrt()
            });
            spheres.chain(boxes).fold(p[1] - scene.floor_height(), f32::min)
        })
        .fold(f32::INFINITY, f32::min)
}

#[test]
fn the_fused_sweep_is_the_kernels_bit_for_bit_at_every_width() {
    let mut scene = Scene::default();
    // Low, so that the sheet reaches the spheres, the box and the floor within the frames.
    scene.cloth.top_center[1] = 0.8;
    scene.boxes.push(Aabb::new([-0.2, 0.0, -0.9], [0.3, 0.6, -0.5]));
    // Sides below, at and above the widest lane group, odd and even; 97 cuts into four
    // bands on two threads, so the bands' edges are crossed too.
    for (n, iters, frames) in [(8u32, 1u32, 90u32), (21, 0, 30), (40, 3, 30), (97, 1, 40)] {
        scene.cloth.n = n;
        let params = SimParams { wind: [1.5, 0.0, -2.0], strain_iterations: iters, ..Default::default() };
        let grab = Grab { particle: n * n / 2 + n / 3, target: [0.1, 1.1, 0.2] };
        compare(&scene, &params, frames, Some(grab));
    }
}

#[test]
fn the_fused_sweep_holds_a_grabbed_pin_and_pins_anywhere() {
    // A tether's pin that is grabbed moves in stage A; the strain passes must read it
    // there. Pins in the last row put a tether's pin below bands that come first.
    let mut scene = Scene::with_n(48);
    scene.cloth.top_center[1] = 0.8;
    scene.cloth.pinning = Pinning::Points(vec![[0, 0], [47, 47], [24, 40]]);
    let params = SimParams::default();
    let grab = Grab { particle: 47 * 48 + 47, target: [0.4, 1.6, 0.3] };
    compare(&scene, &params, 30, Some(grab));
}
