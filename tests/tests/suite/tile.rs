//! The tiled substep (`fusion=tile`, issue 47) on every GPU API: its kernel against its
//! twins and a rollout against the CPU solver, on a grid whose side is no multiple of the
//! tile (37: tiles of 20 with two strain passes, the last one 17 wide, cut by the cloth's
//! edges and corners), pinned corners (tethers), a sphere and a box (colliders in the
//! halo), wind (the faces' wind computed in the tile) and two strain passes (a halo of 6).
//! On llvmpipe every stage is its unfused kernel's arithmetic in the same order, so the
//! bound is exactly 0, as tests/tests/suite/bit_identity.rs holds the other recipes; elsewhere
//! only reported.

use clothlab_core::scene::Aabb;
use clothlab_core::{Scene, SimParams, Solver};
use clothlab_cpu::validate::validate_rollout;
use clothlab_engine::kernels::{SUBSTEP_TILE, TILE_VEL};
use clothlab_engine::recipe::{Command, tile_command, tile_side};
use clothlab_engine::validate::{KernelInput, validate_kernels_with};
use clothlab_engine::{SolverOptions, VariantSpec};
use clothlab_tests::Api;

fn scene() -> Scene {
    let mut s = Scene::with_n(37);
    s.boxes.push(Aabb::new([0.3, 0.0, -0.2], [0.6, 0.9, 0.2]));
    s
}

/// Two strain passes unless said otherwise.
fn params() -> SimParams {
    params_with(2)
}

fn params_with(passes: u32) -> SimParams {
    SimParams { strain_iterations: passes, wind: [3.0, 0.0, 1.5], ..SimParams::default() }
}

fn tile_spec() -> VariantSpec {
    VariantSpec::parse("optimized", &["fusion=tile".into()]).unwrap()
}

fn exact(api: Api, passes: u32) {
    let Some(mut s) = api.solver(tile_spec(), &scene(), &params_with(passes)) else { return };
    let label = api.name();
    let params = || params_with(passes);
    let adapter = s.adapter();
    let kernels: Vec<_> =
        s.recipe_kernels().into_iter().filter(|k| k.def == &SUBSTEP_TILE || k.def == &TILE_VEL).collect();
    assert_eq!(kernels.len(), 2, "{label}: the recipe runs the tiles: {kernels:?}");
    let start = s.state().unwrap();
    let sc = s.scene().clone();
    let mut checks = validate_kernels_with(s.runner(), &kernels, &sc, 0x711e, &params()).unwrap();
    // The temporal loop: two substeps per dispatch (with two passes a halo of 12, tiles of 8:
    // 37 = 4 × 8 + 5), the disturbed cloth with its grab, against the twin's two substeps.
    let input = KernelInput::for_scene(&sc, 0x7e3, &params()).unwrap();
    let mut p = input.p;
    p.tile_substeps = 2;
    assert_eq!(tile_side(p.strain_passes, 2), 32 - 4 * (2 + 2 * passes));
    let tile = kernels[0];
    let commands = [tile_command(tile, input.engine.topology(), p.strain_passes, 2), Command::Swap];
    let mut want = input.for_kernel(tile);
    let mut got = want.clone();
    for v in [&mut got.pos_out, &mut got.aux[0]] {
        v.iter_mut().for_each(|x| *x = [f32::NAN; 4]);
    }
    input.engine.run(&commands, &p, 0, &mut want);
    s.runner().run_commands(&commands, &p, &mut got).unwrap();
    let diff = |a: &[[f32; 4]], b: &[[f32; 4]]| {
        a.iter()
            .flatten()
            .zip(b.iter().flatten())
            .map(|(x, y)| if x == y { 0.0 } else { (x - y).abs() })
            .fold(0.0, f32::max)
    };
    let scale = want.pos.iter().flatten().fold(0.0f32, |m, x| m.max(x.abs()));
    let (dx, dv) = (diff(&got.pos, &want.pos), diff(&got.aux[0], &want.aux[0]));
    println!("{label:8} {passes} passes, two substeps per dispatch: pos max {dx:.2e}, vel max {dv:.2e}");
    assert!(dx.is_finite() && dv.is_finite(), "{label}: the temporal loop left a point unwritten");
    if adapter.contains("llvmpipe") {
        assert_eq!((dx, dv), (0.0, 0.0), "{label} on {adapter}: the temporal loop differs from two twin substeps");
    } else {
        // The kernel's own bound (a disturbed cloth through twelve stages: see SUBSTEP_TILE).
        assert!(dx <= 1e-3 * scale, "{label} on {adapter}: two substeps per dispatch {dx:.2e} off");
    }
    s.set_state(&start).unwrap();
    checks.push(validate_rollout(&mut *s, 4).unwrap());
    for c in &checks {
        println!("{label:8} {passes} passes {:28} {:7} max {:.2e}", c.what, c.buffer, c.max_abs);
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

// One row per API for both tests: they build the same tile kernel (the temporal loop's
// substeps and the tile's side are the dispatch's), and as two rows running at once on the
// harness's two threads each compiled it from a cold shader cache (GL: 45 s apiece);
// one after the other, the second finds it compiled.
clothlab_tests::per_api!(the_tiles_on_each_api);

fn the_tiles_on_each_api(api: Api) {
    the_tiled_substep_is_bit_identical_to_its_twins(api);
    temporal_blocking_folds_substeps_into_one_dispatch_and_keeps_the_bits(api);
}

fn the_tiled_substep_is_bit_identical_to_its_twins(api: Api) {
    // Two passes: a halo of 6, tiles of 20; 37 = 20 + 17 (a partial tile at the far edge).
    // One pass: tiles of 24 (37 = 24 + 13); none: 28 (37 = 28 + 9), where the forces'
    // stage is the last and writes the tile out itself. Two passes run every stage of the
    // tile on every API; one and none (the same WGSL with fewer stages and another tile
    // side: each a pipeline of its own, whose compilation by llvmpipe is most of this
    // test's time) on Vulkan, under the validation layer.
    assert_eq!((tile_side(2, 1), tile_side(1, 1), tile_side(0, 1)), (20, 24, 28));
    let passes: &[u32] = if api == Api::Vulkan { &[2, 1, 0] } else { &[2] };
    for &passes in passes {
        exact(api, passes);
    }
}

fn temporal_spec() -> VariantSpec {
    VariantSpec::parse("optimized", &["fusion=tile".into(), "temporal=on".into()]).unwrap()
}

/// A rollout of `s` (temporal blocking) against the CPU solver: exact on llvmpipe, within
/// the rollout's bound elsewhere.
fn rollout_exact(mut s: Box<dyn Solver>, label: &str, adapter: &str) {
    let c = validate_rollout(&mut *s, 4).unwrap();
    println!("{label:24} {} {:.2e}", c.what, c.max_abs);
    if adapter.contains("llvmpipe") || adapter.is_empty() {
        assert_eq!(c.max_abs, 0.0, "{label} on {adapter}: temporal blocking differs from the CPU");
    } else {
        assert!(c.error <= c.bound, "{label} on {adapter}: {:.2e} over {:.0e}", c.error, c.bound);
    }
}

fn temporal_blocking_folds_substeps_into_one_dispatch_and_keeps_the_bits(api: Api) {
    use clothlab_engine::recipe::{Integration, dispatch_substeps, recipe_for};
    use clothlab_engine::{RecipeSolver, StatsMode};
    // n = 37, two passes: two substeps per dispatch (tiles of 8: four would leave none);
    // n = 24 fits one region: the whole frame of 16 substeps in one dispatch.
    for (n, group) in [(37, 2), (24, 16)] {
        let mut sc = scene();
        sc.cloth.n = n;
        let p = params();
        if api == Api::Vulkan {
            // The recipe and the CPU engine's rollout of it, once (they are no API's).
            let v = temporal_spec().resolve(&clothlab_tests::EVERY_CAP, "vulkan").unwrap();
            let (_, topo) = clothlab_core::build(&sc, &p).unwrap();
            assert_eq!(dispatch_substeps(&v, Integration::of(&p), p.strain_iterations, &topo), group, "n = {n}");
            // Two dispatches per recording (the tiles, the velocities' copy), whatever the group.
            let cmds = recipe_for(&v, p.strain_iterations, Integration::of(&p), &topo);
            assert_eq!(cmds.iter().filter(|c| c.kernel().is_some()).count(), 2, "n = {n}: {cmds:?}");
            let cpu = RecipeSolver::new(clothlab_cpu::Exec::Serial, v, sc.clone(), p.clone()).unwrap();
            rollout_exact(Box::new(cpu), &format!("cpu engine n={n}"), "");
        }
        let Some(s) = api.solver(temporal_spec(), &sc, &p) else { return };
        let a = s.adapter();
        rollout_exact(s.into_solver(), &format!("{api} n={n}"), &a);
        if api == Api::Vulkan {
            // Per-substep statistics cannot be had between the substeps of one dispatch.
            let stats = SolverOptions { stats: StatsMode::Atomics };
            let e = clothlab_vulkan::vulkan_solver(temporal_spec(), sc.clone(), p.clone(), true, stats).err().unwrap();
            assert!(e.to_string().contains("temporal=off"), "{e}");
        }
    }
}
