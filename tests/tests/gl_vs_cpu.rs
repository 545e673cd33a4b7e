//! The OpenGL backend against the CPU twins: every kernel flavor GL can run, rollouts of
//! each preset, the spring table from storage and from a texture, the statistics. Any GL
//! error or debug message of medium or high severity fails the test that caused it
//! (`Engine::check`).

use clothlab_core::validate::validate_rollout;
use clothlab_core::{Scene, SimParams, Solver, SolverError};
use clothlab_engine::recipe::StatsMode;
use clothlab_engine::validate::{KernelRunner, flavors, validate_kernels};
use clothlab_engine::{SolverOptions, Variant, VariantSpec};
use clothlab_gl::{GlSolver, gl_solver};
use clothlab_tests::{assert_checks, assert_kernels_match_twins, assert_stats_match_twin, or_skip};

fn gl(variant: impl Into<VariantSpec>, n: u32) -> Option<GlSolver> {
    or_skip(gl_solver(variant, Scene::with_n(n), SimParams::default(), SolverOptions::default()), "gl solver")
}

fn no_gl_errors(s: &mut GlSolver) {
    s.check("the test").unwrap();
}

#[test]
fn every_gl_kernel_matches_its_cpu_twin() {
    for n in [64, 65] {
        let Some(mut v) = gl(Variant::OPTIMIZED, n) else { return };
        // GL has no push constants: no `_imm` flavor is offered.
        assert!(!v.caps().immediates);
        let kernels = if n == 64 { flavors(&v.caps(), false) } else { v.kernels() };
        let names: Vec<String> = kernels.iter().map(|k| k.shader_name()).collect();
        let has = |n: &str| names.iter().any(|k| k == n);
        assert!(has("forces_springs") && has("springs_scatter"), "{names:?}");
        assert!(names.iter().all(|k| !k.ends_with("_imm")), "{names:?}");
        if n == 64 {
            assert!(has("forces_integrate_collide_cu_sto") && has("strain_limit_sto"), "{names:?}");
            if v.caps().float_atomics {
                assert!(has("springs_scatter_f32") && has("tri_normals_scatter_f32_sto"), "{names:?}");
            }
        }
        assert_kernels_match_twins(&mut v, &kernels, n, 0x5eed + n as u64, 13, &format!("gl n={n}"));
        no_gl_errors(&mut v);
    }
}

#[test]
fn gl_rollouts_stay_close_to_the_cpu() {
    for variant in [Variant::NAIVE, Variant::OPTIMIZED, Variant::THESIS] {
        let Some(mut v) = gl(variant, 64) else { return };
        let c = validate_rollout(&mut v, 13).unwrap();
        assert_checks(v.name(), &[c]);
        no_gl_errors(&mut v);
    }
}

#[test]
fn the_spring_table_from_storage_or_a_texture_gives_the_twins_results_on_gl() {
    for table in ["storage", "uniform", "image"] {
        let spec = VariantSpec::parse("optimized", &[format!("table={table}")]).unwrap();
        let Some(mut v) = gl(spec.clone(), 65) else { return };
        let kernels = if table == "image" { flavors(&v.caps(), true) } else { v.kernels() };
        if table == "image" {
            let names: Vec<String> = kernels.iter().map(|k| k.shader_name()).collect();
            assert!(names.iter().any(|k| k == "forces_springs_tex_sto"), "{names:?}");
        }
        let checks = validate_kernels(&mut v, &kernels, 65, 0x7ab1e).unwrap();
        assert_checks(&format!("gl table={table}"), &checks);
        no_gl_errors(&mut v);
        let Some(mut v) = gl(spec, 65) else { return };
        let c = validate_rollout(&mut v, 6).unwrap();
        assert_checks(&format!("gl table={table} rollout"), &[c]);
        no_gl_errors(&mut v);
    }
}

#[test]
fn push_constants_are_refused_on_gl_in_one_line() {
    let spec = VariantSpec::parse("optimized", &["constants=push".to_string()]).unwrap();
    match gl_solver(spec, Scene::with_n(16), SimParams::default(), SolverOptions::default()) {
        Err(e) => {
            let msg = e.to_string();
            assert!(!msg.contains('\n') && msg.contains("immediates"), "{msg}");
        }
        Ok(_) => panic!("constants=push accepted on GL, which has no push constants"),
    }
}

#[test]
fn gl_statistics_match_the_cpu_twin() {
    // As the Vulkan test (bounds and reasons there): by atomics always; by subgroups only
    // where GL_KHR_shader_subgroup is (refused in one line elsewhere).
    let n = 65;
    for (variant, stats, energy_bound) in [
        (Variant::OPTIMIZED, StatsMode::Subgroups, 1e-4),
        (Variant::OPTIMIZED, StatsMode::Atomics, 2.5e-4),
        (Variant::NAIVE, StatsMode::Atomics, 2.5e-4),
    ] {
        let options = SolverOptions { stats };
        let v = match gl_solver(variant, Scene::with_n(n), SimParams::default(), options) {
            Ok(v) => Some(v),
            Err(e @ SolverError::Unsupported(_)) => {
                assert_eq!(stats, StatsMode::Subgroups, "{e}");
                assert!(!e.to_string().contains('\n'), "{e}");
                eprintln!("refused {stats:?}: {e}");
                None
            }
            Err(e) => or_skip(Err(e), "gl solver"),
        };
        let Some(mut v) = v else { continue };
        assert_stats_match_twin(&mut v, energy_bound);
        no_gl_errors(&mut v);
    }
}
