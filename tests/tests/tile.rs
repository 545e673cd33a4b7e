//! The tiled substep (`fusion=tile`, issue 47) on every GPU API: its kernel against its
//! twins and a rollout against the CPU solver, on a grid whose side is no multiple of the
//! tile (37: tiles of 20 with two strain passes, the last one 17 wide, cut by the cloth's
//! edges and corners), pinned corners (tethers), a sphere and a box (colliders in the
//! halo), wind (the faces' wind computed in the tile) and two strain passes (a halo of 6).
//! On llvmpipe every stage is its unfused kernel's arithmetic in the same order, so the
//! bound is exactly 0, as tests/tests/bit_identity.rs holds the other recipes; elsewhere
//! only reported. One solver per API: llvmpipe compiles the tile's shader at its first
//! dispatch, for about two minutes.

use clothlab_core::scene::Aabb;
use clothlab_core::validate::validate_rollout;
use clothlab_core::{Scene, SimParams, Solver};
use clothlab_engine::kernels::{SUBSTEP_TILE, TILE_VEL};
use clothlab_engine::recipe::tile_side;
use clothlab_engine::validate::validate_kernels_with;
use clothlab_engine::{Engine, GpuSolver, SolverOptions, VariantSpec};
use clothlab_tests::or_skip;

fn scene() -> Scene {
    let mut s = Scene::with_n(37);
    s.boxes.push(Aabb::new([0.3, 0.0, -0.2], [0.6, 0.9, 0.2]));
    s
}

fn params() -> SimParams {
    SimParams { strain_iterations: 2, wind: [3.0, 0.0, 1.5], ..SimParams::default() }
}

fn tile_spec() -> VariantSpec {
    VariantSpec::parse("optimized", &["fusion=tile".into()]).unwrap()
}

fn exact<E: Engine>(s: Option<GpuSolver<E>>, label: &str) {
    let Some(mut s) = s else { return };
    let adapter = s.adapter();
    let kernels: Vec<_> =
        s.recipe_kernels().into_iter().filter(|k| k.def == &SUBSTEP_TILE || k.def == &TILE_VEL).collect();
    assert_eq!(kernels.len(), 2, "{label}: the recipe runs the tiles: {kernels:?}");
    let start = s.state().unwrap();
    let sc = s.scene().clone();
    let mut checks = validate_kernels_with(&mut s, &kernels, &sc, 0x711e, &params()).unwrap();
    s.set_state(&start).unwrap();
    checks.push(validate_rollout(&mut s, 4).unwrap());
    for c in &checks {
        println!("{label:8} {:28} {:7} max {:.2e}", c.what, c.buffer, c.max_abs);
    }
    if !adapter.contains("llvmpipe") {
        println!("{label}: {adapter} is not llvmpipe: exactness not required");
        for c in &checks {
            assert!(
                c.error <= c.bound,
                "{label} on {adapter}: {} {} {:.2e} over {:.0e}",
                c.what,
                c.buffer,
                c.error,
                c.bound
            );
        }
        return;
    }
    for c in &checks {
        assert_eq!(c.max_abs, 0.0, "{label} on {adapter}: {} {} differs from the CPU twin", c.what, c.buffer);
    }
}

#[test]
fn the_tiled_substep_is_bit_identical_to_its_twins_on_every_api() {
    // Two passes: a halo of 6, tiles of 20; 37 = 20 + 17 (a partial tile at the far edge).
    assert_eq!(tile_side(2, 1), 20);
    let o = SolverOptions::default;
    exact(or_skip(clothlab_vulkan::vulkan_solver(tile_spec(), scene(), params(), true, o()), "vulkan"), "vulkan");
    exact(or_skip(clothlab_wgpu::wgpu_solver(tile_spec(), scene(), params(), o()), "wgpu"), "wgpu");
    exact(or_skip(clothlab_gl::gl_solver(tile_spec(), scene(), params(), o()), "gl"), "gl");
}
