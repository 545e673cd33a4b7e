//! A kernel added from outside — a WGSL string and its CPU twin — and a recipe that uses
//! it, run on the CPU engine, wgpu, Vulkan and GL without editing any backend; and the
//! bisection of rollouts on every GPU API.

use clothlab_core::layout::Buf;
use clothlab_core::{Scene, SimParams, SolverError};
use clothlab_cpu::Exec;
use clothlab_engine::SolverOptions;
use clothlab_engine::kernels::{Check, Count, HostBuffers, KernelDef, Source, TwinArgs, Variants};
use clothlab_engine::recipe::{Command, run};
use clothlab_engine::validate::{COMPARED_BUFFERS, KernelInput, KernelRunner, bisect, validate_kernels};
use clothlab_engine::{CpuEngine, Variant};
use clothlab_gl::gl_solver;
use clothlab_tests::{assert_checks, or_skip};
use clothlab_vulkan::vulkan_solver;
use clothlab_wgpu::wgpu_solver;

/// The twin: halves every particle's force (exact in f32, so GPU and CPU agree bit for bit).
fn halve_force(_: &TwinArgs, b: &mut HostBuffers) {
    for f in &mut b.force {
        for c in f.iter_mut().take(3) {
            *c *= 0.5;
        }
    }
}

/// A kernel from outside the crates: one table row, its WGSL given as a string.
static HALVE_FORCE: KernelDef = KernelDef {
    source: Source::Wgsl {
        includes: &["state"],
        body: "
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let f = force[i];
    force[i] = vec4<f32>(0.5 * f.xyz, f.w);
}
",
    },
    check: Check::Bound { relative: 0.0, reason: "one exact multiplication by 0.5" },
    label: "halve_force",
    variants: Variants::NONE,
    ..KernelDef::new("halve_force", halve_force, Count::Particles, &[Buf::Params, Buf::Force], &[Buf::Force])
};

/// The same with a type error on its line 3.
static BROKEN: KernelDef = KernelDef {
    name: "broken",
    source: Source::Wgsl {
        includes: &["state"],
        body: "@compute @workgroup_size(WORKGROUP)\nfn main() {\n    let x: f32 = 1u;\n}\n",
    },
    ..HALVE_FORCE
};

/// The runners with the variant each resolved `Variant::OPTIMIZED` to (GL has no push
/// constants: its optimized recipe keeps the constants in a uniform block).
fn runners(n: u32) -> Vec<(Box<dyn KernelRunner>, Variant)> {
    let scene = Scene::with_n(n);
    let params = SimParams::default();
    let mut v: Vec<(Box<dyn KernelRunner>, Variant)> = Vec::new();
    let (_, topo) = clothlab_core::build(&scene, &params).unwrap();
    v.push((Box::new(CpuEngine::new(Exec::Serial, scene.clone(), topo)), Variant::OPTIMIZED));
    if let Some(g) =
        or_skip(wgpu_solver(Variant::OPTIMIZED, scene.clone(), params.clone(), SolverOptions::default()), "wgpu")
    {
        let spec = g.variant();
        v.push((Box::new(g), spec));
    }
    let options = SolverOptions::default();
    if let Some(k) = or_skip(vulkan_solver(Variant::OPTIMIZED, scene.clone(), params.clone(), true, options), "vulkan")
    {
        let spec = k.variant();
        v.push((Box::new(k), spec));
    }
    // GL: naga's GLSL of the composed WGSL, compiled by the driver when added.
    if let Some(g) = or_skip(gl_solver(Variant::OPTIMIZED, scene, params, SolverOptions::default()), "gl") {
        let spec = g.variant();
        v.push((Box::new(g), spec));
    }
    v
}

#[test]
fn a_kernel_defined_outside_runs_validated_on_every_engine_and_in_a_recipe() {
    let n = 33;
    for (mut r, variant) in runners(n) {
        let name = r.adapter();
        if !name.contains("CPU engine") {
            // Not built in: the backend compiles it when asked (naga to SPIR-V on Vulkan).
            assert!(!r.kernels().contains(&HALVE_FORCE.plain()), "{name}");
        }
        r.add_kernel(HALVE_FORCE.plain()).unwrap_or_else(|e| panic!("{name}: {e}"));
        let checks = validate_kernels(r.as_mut(), &[HALVE_FORCE.plain()], n, 3).unwrap();
        assert_eq!(checks.len(), COMPARED_BUFFERS);
        assert_checks(&name, &checks);
        // A recipe that uses it: the optimized step with the force halved before the
        // integration, three substeps from the disturbed cloth, against the CPU engine.
        // Bit for bit: the optimized kernels are (checked elsewhere) and so is this one.
        let input = KernelInput::new(n, 11).unwrap();
        let mut commands = clothlab_engine::recipe::recipe(&variant, 1, clothlab_engine::recipe::Integration::VERLET);
        commands.splice(1..1, run(HALVE_FORCE.plain()));
        let (mut want, mut got) = (input.bufs.clone(), input.bufs.clone());
        for _ in 0..3 {
            input.engine.run(&commands, &input.p, 0, &mut want);
            r.run_commands(&commands, &input.p, &mut got).unwrap();
        }
        assert!(got.pos == want.pos && got.force == want.force, "{name}: the recipe with the added kernel differs");
        assert!(want.pos != input.bufs.pos);
    }
}

#[test]
fn a_kernel_that_does_not_compile_is_refused_with_the_compilers_message() {
    for (mut r, _) in runners(8).into_iter().skip(1) {
        let name = r.adapter();
        match r.add_kernel(BROKEN.plain()) {
            Err(SolverError::Shader { kernel, reason }) => {
                assert_eq!(kernel, "broken");
                // naga's message names the file and the mistake.
                assert!(reason.contains("broken.wgsl") && reason.contains("f32"), "{name}: {reason}");
            }
            other => panic!("{name}: expected a shader error, got {:?}", other.map(|_| ())),
        }
        // The runner still works afterwards.
        let kernels = r.kernels();
        assert!(!kernels.iter().any(|k| k.def.name == "broken"));
    }
}

#[test]
fn bisection_on_every_gpu_api_finds_no_kernel_out_of_bounds() {
    // On a driver that computes the twins' results (lavapipe: the optimized kernels are
    // bit-exact, the naive scatters within 1e-6 m per substep), every split stays within
    // the rollout bound and no culprit is named.
    let scene = Scene::with_n(24);
    let params = SimParams::default();
    for variant in [Variant::NAIVE, Variant::OPTIMIZED] {
        let mut gpu: Vec<(Box<dyn KernelRunner>, Vec<Command>)> = Vec::new();
        if let Some(g) = or_skip(wgpu_solver(variant, scene.clone(), params.clone(), SolverOptions::default()), "wgpu")
        {
            let c = g.commands().to_vec();
            gpu.push((Box::new(g), c));
        }
        let options = SolverOptions::default();
        if let Some(v) = or_skip(vulkan_solver(variant, scene.clone(), params.clone(), true, options), "vulkan") {
            let c = v.commands();
            gpu.push((Box::new(v), c));
        }
        if let Some(g) = or_skip(gl_solver(variant, scene.clone(), params.clone(), SolverOptions::default()), "gl") {
            let c = g.commands().to_vec();
            gpu.push((Box::new(g), c));
        }
        for (mut r, commands) in gpu {
            let b = bisect(r.as_mut(), &commands, &scene, &params, 48).unwrap();
            let checks: Vec<_> = b.splits.iter().map(|s| s.check.clone()).collect();
            assert_checks(&format!("{variant:?}"), &checks);
            assert_eq!(b.culprit, None);
            assert_eq!(b.splits.len(), clothlab_engine::recipe::dispatches(&commands).count());
        }
    }
}
