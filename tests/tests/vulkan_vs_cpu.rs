//! The Vulkan backend against the CPU twins, with the Khronos validation layer on: any
//! message it reports fails the test that caused it.

use clothlab_core::validate::{KernelRunner, validate_kernels, validate_rollout};
use clothlab_core::{Scene, SimParams, Solver};
use clothlab_shaders::recipe::Variant;
use clothlab_tests::{assert_checks, gpu_required};
use clothlab_vulkan::VulkanSolver;

fn vulkan(variant: Variant, n: u32) -> Option<VulkanSolver> {
    match VulkanSolver::new(variant, Scene::with_n(n), SimParams::default(), true) {
        Ok(s) => Some(s),
        Err(e)
            if !gpu_required()
                && (e.to_string().contains("no GPU adapter") || e.to_string().contains("no Vulkan loader")) =>
        {
            eprintln!("skipped: {e}");
            None
        }
        Err(e) => panic!("vulkan solver: {e}"),
    }
}

fn no_validation_messages(s: &VulkanSolver) {
    let m = s.take_validation_messages();
    assert!(m.is_empty(), "validation layer: {m:#?}");
}

#[test]
fn every_vulkan_kernel_matches_its_cpu_twin() {
    for n in [64, 65] {
        let Some(mut v) = vulkan(Variant::Optimized, n) else { return };
        let names = v.kernel_names();
        assert!(names.contains(&"forces_springs") && names.contains(&"springs_scatter"), "{names:?}");
        if v.float_atomics() {
            assert!(names.contains(&"springs_scatter_f32") && names.contains(&"tri_normals_scatter_f32"), "{names:?}");
        }
        let checks = validate_kernels(&mut v, n, 0x5eed + n as u64).unwrap();
        assert_eq!(checks.len(), 5 * names.len());
        assert_checks(&format!("vk n={n}"), &checks);
        no_validation_messages(&v);
    }
}

#[test]
fn vulkan_rollouts_stay_close_to_the_cpu() {
    for variant in [Variant::Naive, Variant::Optimized] {
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
    for variant in [Variant::Naive, Variant::Optimized] {
        let Some(mut v) = vulkan(variant, 48) else { return };
        v.set_params(params.clone()).unwrap();
        let c = validate_rollout(&mut v, 8).unwrap();
        assert_checks(&format!("{} set_params", v.name()), &[c]);
        no_validation_messages(&v);
    }
}
