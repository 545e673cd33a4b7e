//! The Vulkan backend against the CPU twins, with the Khronos validation layer on: any
//! message it reports fails the test that caused it.

use clothlab_core::validate::validate_rollout;
use clothlab_core::{Scene, SimParams, Solver};
use clothlab_engine::validate::{KernelRunner, flavors, validate_kernels};
use clothlab_engine::{Variant, VariantSpec};
use clothlab_tests::{assert_checks, assert_kernels_match_twins, assert_stats_match_twin, or_skip};
use clothlab_vulkan::{SolverOptions, StatsMode, VulkanSolver, vulkan_solver};

fn vulkan(variant: Variant, n: u32) -> Option<VulkanSolver> {
    vulkan_with(variant, n, SolverOptions::default())
}

fn vulkan_with(variant: impl Into<VariantSpec>, n: u32, options: SolverOptions) -> Option<VulkanSolver> {
    or_skip(vulkan_solver(variant, Scene::with_n(n), SimParams::default(), true, options), "vulkan solver")
}

fn no_validation_messages(s: &VulkanSolver) {
    let m = s.engine().take_validation_messages();
    assert!(m.is_empty(), "validation layer: {m:#?}");
}

#[test]
fn every_vulkan_kernel_matches_its_cpu_twin() {
    // n = 64 with every flavor (every switch); n = 65 with what the solver built (the
    // optimized recipe and the plain flavor of each kernel), the last block partly empty.
    for n in [64, 65] {
        let Some(mut v) = vulkan(Variant::OPTIMIZED, n) else { return };
        let kernels = if n == 64 { flavors(&v.caps(), false) } else { v.kernels() };
        let names: Vec<String> = kernels.iter().map(|k| k.shader_name()).collect();
        let has = |n: &str| names.iter().any(|k| k == n);
        assert!(has("forces_springs") && has("springs_scatter"), "{names:?}");
        if n == 64 {
            assert!(has("forces_integrate_collide_cu_imm") && has("strain_limit_sto"), "{names:?}");
            if v.caps().float_atomics {
                assert!(has("springs_scatter_f32") && has("tri_normals_scatter_f32_sto"), "{names:?}");
            }
        }
        assert_kernels_match_twins(&mut v, &kernels, n, 0x5eed + n as u64, 13, &format!("vk n={n}"));
        no_validation_messages(&v);
    }
}

#[test]
fn vulkan_rollouts_stay_close_to_the_cpu() {
    for variant in [Variant::NAIVE, Variant::OPTIMIZED, Variant::THESIS] {
        let Some(mut v) = vulkan(variant, 64) else { return };
        let c = validate_rollout(&mut v, 13).unwrap();
        assert_checks(v.name(), &[c]);
        no_validation_messages(&v);
    }
}

#[test]
fn changed_parameters_reach_the_vulkan_kernels() {
    // Stiffer bend springs, two strain passes and wind: a rollout with them must still
    // match the CPU solver given the same parameters (bound as in validate_rollout).
    let params = SimParams { bend_stiffness: 0.1, strain_iterations: 2, wind: [2.0, 0.0, 1.0], ..SimParams::default() };
    // Wind and gravity alone leave the spring tables as they are (no upload): they must
    // still reach the kernels through the frame's constants. (A gustier scene, wind
    // (-1.5, 0.5, 2) with gravity -6, makes the naive scatter's rounding grow to 3.1e-4 m
    // in 128 substeps, over ROLLOUT_BOUND_PER_SUBSTEP, with or without a table upload:
    // measured on lavapipe; the optimized variants stay bit-exact.)
    let light = SimParams { wind: [2.0, 0.0, 1.0], gravity: [0.0, -9.0, 0.0], ..SimParams::default() };
    for (what, p) in [("tables", &params), ("constants only", &light)] {
        for variant in [Variant::NAIVE, Variant::OPTIMIZED] {
            let Some(mut v) = vulkan(variant, 48) else { return };
            v.set_params(p.clone()).unwrap();
            let c = validate_rollout(&mut v, 8).unwrap();
            assert_checks(&format!("{} set_params {what}", v.name()), &[c]);
            no_validation_messages(&v);
        }
    }
}

#[test]
fn the_spring_table_from_storage_or_an_image_gives_the_twins_results() {
    // With the interior's uniform constants off, every particle reads its slots from the
    // table: from read-only storage buffers, or from a sampled image (texture memory).
    // Same arithmetic as the twins, so the kernel bounds of validate_kernels apply; and a
    // rollout stays within the rollout bound.
    for table in ["storage", "image"] {
        let spec = VariantSpec::parse("optimized", &[format!("table={table}")]).unwrap();
        let Some(mut v) = vulkan_with(spec.clone(), 65, SolverOptions::default()) else { return };
        let kernels = if table == "image" { flavors(&v.caps(), true) } else { v.kernels() };
        if table == "image" {
            let names: Vec<String> = kernels.iter().map(|k| k.shader_name()).collect();
            assert!(names.iter().any(|k| k == "forces_springs_tex_sto"), "{names:?}");
            assert!(names.iter().any(|k| k.starts_with("strain_limit_tex")), "{names:?}");
            // Every kernel of the recipe that reads the table reads it from the image.
            let recipe = v.recipe_kernels();
            assert!(recipe.iter().all(|k| !k.def.variants.table_image || k.flavor.table_image), "{recipe:?}");
        }
        let checks = validate_kernels(&mut v, &kernels, 65, 0x7ab1e).unwrap();
        assert_checks(&format!("table={table}"), &checks);
        no_validation_messages(&v);
        // A fresh solver: the kernel checks left the disturbed state in this one.
        let Some(mut v) = vulkan_with(spec, 65, SolverOptions::default()) else { return };
        let c = validate_rollout(&mut v, 6).unwrap();
        assert_checks(&format!("table={table} rollout"), &[c]);
        no_validation_messages(&v);
    }
}

#[test]
fn gpu_statistics_match_the_cpu_twin_by_subgroups_and_by_atomics() {
    // n = 65: 4225 particles, the last workgroup partly empty. The max strain is a max of
    // the same f32 values the twin computes (length and a division: within 4 ulps of
    // ~1.1, so 1e-6 absolute). The energy is a sum of 4225 positive terms in another
    // order than the twin's f64 sum: by atomics in any order, relative error below
    // N·2^-24 = 2.5e-4; by subgroups a tree of depth ~log2(N) plus 67 partials in
    // sequence, so below 1e-4 too (measured on lavapipe: ~1e-7 both).
    let n = 65;
    for (variant, stats, energy_bound) in [
        (Variant::OPTIMIZED, StatsMode::Subgroups, 1e-4),
        (Variant::OPTIMIZED, StatsMode::Atomics, 2.5e-4),
        (Variant::NAIVE, StatsMode::Atomics, 2.5e-4),
    ] {
        let options = SolverOptions { stats };
        let v = match vulkan_solver(variant, Scene::with_n(n), SimParams::default(), true, options) {
            Ok(v) => Some(v),
            Err(e @ clothlab_core::SolverError::Unsupported(_)) => {
                // A device without subgroup arithmetic refuses the mode with a message.
                eprintln!("skipped {stats:?}: {e}");
                None
            }
            Err(e) => or_skip(Err(e), "vulkan solver"),
        };
        let Some(mut v) = v else { continue };
        assert_stats_match_twin(&mut v, energy_bound);
        no_validation_messages(&v);
    }
}

#[test]
fn dropping_the_solver_frees_every_allocation() {
    let options = SolverOptions { stats: StatsMode::Atomics };
    let spec = VariantSpec::parse("naive", &["table=image".into()]).unwrap();
    let Some(mut v) = vulkan_with(spec, 33, options) else { return };
    v.step_frame().unwrap();
    let dev = v.engine().device();
    // 24 buffers (state, tables, constants, statistics, staging) and the table image.
    assert!(dev.live_allocations() >= 25, "{} allocations", dev.live_allocations());
    drop(v);
    assert_eq!(dev.live_allocations(), 0, "gpu-allocator still holds allocations after the solver is gone");
}
