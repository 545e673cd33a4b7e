//! The wgpu kernels and solvers against the CPU twins (bounds and their reasons: the rows
//! of `clothlab_engine::kernels`).

use clothlab_core::validate::{compare, validate_rollout};
use clothlab_core::{Scene, SimParams, Solver};
use clothlab_engine::VariantSpec;
use clothlab_engine::kernels::{self as k, Check};
use clothlab_engine::validate::{COMPARED_BUFFERS, KernelRunner, flavors, validate_kernels};
use clothlab_tests::{assert_checks, or_skip};
use clothlab_wgpu::{SolverOptions, Variant, WgpuSolver, wgpu_solver};

/// A wgpu solver, or `None` (with the reason printed) where no adapter exists and the
/// environment does not require one.
fn gpu(variant: Variant, n: u32) -> Option<WgpuSolver> {
    or_skip(wgpu_solver(variant, Scene::with_n(n), SimParams::default(), SolverOptions::default()), "wgpu solver")
}

fn kernels_match_on(n: u32, every_flavor: bool) {
    let Some(mut g) = gpu(Variant::OPTIMIZED, n) else { return };
    // Every flavor (every switch: where constants, colliders live, which atomics), or the
    // kernels the solver built: the optimized recipe's and the plain flavor of each.
    let kernels = if every_flavor { flavors(&g.caps(), false) } else { g.kernels() };
    let names: Vec<String> = kernels.iter().map(|k| k.shader_name()).collect();
    let has = |n: &str| names.iter().any(|k| k == n);
    for def in [
        &k::FORCES,
        &k::SPRINGS,
        &k::SPRINGS_SCATTER,
        &k::INTEGRATE,
        &k::COLLIDE,
        &k::FORCES_INTEGRATE_COLLIDE,
        &k::TRI_NORMALS_SCATTER,
        &k::VERTEX_NORMALS_NAIVE,
        &k::FORCES_SPRINGS,
        &k::INTEGRATE_COLLIDE,
        &k::STRAIN_LIMIT,
        &k::TRI_NORMALS,
        &k::VERTEX_NORMALS,
    ] {
        assert!(has(def.name), "kernel {} missing", def.name);
        if every_flavor {
            assert!(has(&format!("{}_sto", def.name)), "{}_sto missing", def.name);
            assert_eq!(has(&format!("{}_imm", def.name)), g.caps().immediates, "{}_imm", def.name);
        }
    }
    if every_flavor {
        assert!(has("integrate_collide_cu") && has("forces_integrate_collide_cu_imm") == g.caps().immediates);
        if g.caps().float_atomics {
            assert!(has("springs_scatter_f32") && has("tri_normals_scatter_f32_sto"));
        } else {
            println!("float atomics not available on this adapter: only the compare-exchange path is tested");
        }
    }
    let checks = validate_kernels(&mut g, &kernels, n, 0x5eed + n as u64).unwrap();
    // Those with a bound that run on a grid (the mesh's XPBD pass is tests/tests/mesh_gpu.rs's).
    let bounded = kernels
        .iter()
        .filter(|k| matches!(k.def.check, Check::Bound { .. }) && k.def.cloths != k::Cloths::Mesh)
        .count();
    // No statistics kernels (wgpu builds them only with the option); the one other kernel
    // with a test of its own is the hash's scatter (tests/tests/self_collision.rs).
    let own: Vec<String> =
        kernels.iter().filter(|k| !matches!(k.def.check, Check::Bound { .. })).map(|k| k.shader_name()).collect();
    assert!(own.iter().all(|k| k.starts_with("hash_scatter")), "kernels checked elsewhere: {own:?}");
    assert_eq!(checks.len(), COMPARED_BUFFERS * bounded);
    assert_checks(&format!("n = {n}"), &checks);
}

#[test]
fn every_kernel_matches_its_cpu_twin_at_n_64() {
    kernels_match_on(64, true);
}

#[test]
fn every_kernel_matches_its_cpu_twin_at_sizes_that_are_not_multiples_of_64() {
    for n in [63, 65, 257] {
        kernels_match_on(n, false);
    }
}

#[test]
fn rollouts_of_200_substeps_stay_close_to_the_cpu() {
    let frames = 13; // 208 substeps of the default 16 per frame
    let Some(mut naive) = gpu(Variant::NAIVE, 64) else { return };
    let Some(mut opt) = gpu(Variant::OPTIMIZED, 64) else { return };
    let a = validate_rollout(&mut naive, frames).unwrap();
    let b = validate_rollout(&mut opt, frames).unwrap();
    // Naive against optimized: both differ from the CPU within the bound, so from each
    // other within twice of it.
    let mut ab = compare("naive vs opt", "pos", &naive.state().unwrap().pos, &opt.state().unwrap().pos, false, 0.0);
    ab.bound = 2.0 * a.bound;
    ab.error = ab.max_abs;
    assert_checks("rollout", &[a, b, ab]);
}

#[test]
fn changed_parameters_reach_the_wgpu_kernels() {
    // As for Vulkan: after set_params, a rollout still matches the CPU with the new values.
    let params = SimParams { bend_stiffness: 0.1, strain_iterations: 2, wind: [2.0, 0.0, 1.0], ..SimParams::default() };
    // Wind and gravity alone leave the spring tables as they are (no upload): they must
    // still reach the kernels through the frame's constants. (A gustier scene, wind
    // (-1.5, 0.5, 2) with gravity -6, makes the naive scatter's rounding grow to 3.1e-4 m
    // in 128 substeps, over ROLLOUT_BOUND_PER_SUBSTEP, with or without a table upload:
    // measured on lavapipe; the optimized variants stay bit-exact.)
    let light = SimParams { wind: [2.0, 0.0, 1.0], gravity: [0.0, -9.0, 0.0], ..SimParams::default() };
    for (what, p) in [("tables", &params), ("constants only", &light)] {
        for variant in [Variant::NAIVE, Variant::OPTIMIZED] {
            let Some(mut g) = gpu(variant, 48) else { return };
            g.set_params(p.clone()).unwrap();
            let c = validate_rollout(&mut g, 8).unwrap();
            assert_checks(&format!("{} set_params {what}", g.name()), &[c]);
        }
    }
}

#[test]
fn the_spring_table_from_a_texture_gives_the_twins_results_on_wgpu_too() {
    // The thesis's texture memory on wgpu: every `_tex` flavor against its twin (bounds of
    // the rows), then the thesis preset (springs scattered, the strain limit reading the
    // image) rolled out, with stiffer springs set midway so that the image is rewritten.
    let spec = VariantSpec::parse("optimized", &["table=image".into()]).unwrap();
    let Some(mut g) =
        or_skip(wgpu_solver(spec, Scene::with_n(65), SimParams::default(), SolverOptions::default()), "wgpu solver")
    else {
        return;
    };
    let tex: Vec<_> = flavors(&g.caps(), true).into_iter().filter(|k| k.flavor.table_image).collect();
    assert!(tex.len() >= 9, "{tex:?}");
    let checks = validate_kernels(&mut g, &tex, 65, 0x7ab1e).unwrap();
    assert_checks("wgpu table=image", &checks);
    let Some(mut t) = gpu(Variant::THESIS, 48) else { return };
    assert_eq!(t.name(), "wgpu-thesis");
    t.set_params(SimParams { bend_stiffness: 0.1, ..SimParams::default() }).unwrap();
    let c = validate_rollout(&mut t, 8).unwrap();
    assert_checks("wgpu thesis rollout", &[c]);
}
