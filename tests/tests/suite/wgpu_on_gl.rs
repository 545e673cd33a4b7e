//! wgpu on its GL backend (`--wgpu-backend gl`): the fourth stack, beside raw GL as
//! wgpu-on-Vulkan stands beside raw Vulkan. Each test opens its wgpu contexts on the
//! backend it names (`GpuContext::with_backends`), never through the process-wide choice
//! that the other tests of this binary leave unset. Every flavor the adapter offers against its CPU twin (the
//! rows' bounds), rollouts of both recipes, and the wgpu renderer's picture on GL against
//! the same state drawn by wgpu on Vulkan.

use clothlab_core::{RenderMode, Scene, SimParams, Solver};
use clothlab_cpu::validate::validate_rollout;
use clothlab_engine::validate::flavors;
use clothlab_tests::{assert_checks, assert_kernels_match_twins, image_diff, or_skip, test_view};
use clothlab_wgpu::{ClothSource, GpuContext, GpuSolver, SolverOptions, Variant, WgpuEngine, WgpuRenderer, WgpuSolver};

/// A wgpu solver on GL for `scene`, or `None` where no adapter exists and none is required.
fn gl_solver_of(variant: Variant, scene: Scene, params: SimParams) -> Option<WgpuSolver> {
    let ctx = or_skip(GpuContext::with_backends(wgpu::Backends::GL), "wgpu on GL")?;
    Some(GpuSolver::new(WgpuEngine::on(ctx), variant, scene, params, SolverOptions::default()).unwrap())
}

/// A wgpu solver on GL, or `None` where no adapter exists and none is required.
fn on_gl(variant: Variant, n: u32) -> Option<WgpuSolver> {
    let s = gl_solver_of(variant, Scene::with_n(n), SimParams::default())?;
    // The choice reached wgpu: the adapter is a GL one.
    assert_eq!(s.engine().context().info.backend, wgpu::Backend::Gl, "{}", s.engine().context().describe());
    Some(s)
}

#[test]
fn every_kernel_wgpu_runs_on_gl_matches_its_cpu_twin() {
    let Some(mut g) = on_gl(Variant::OPTIMIZED, 64) else { return };
    // wgpu's GL backend offers no float atomics and no subgroups: the flavors that remain
    // (compare-exchange, uniform/storage/immediate constants, colliders in uniforms; the
    // table image needs a solver made with table=image, tested on wgpu-on-Vulkan).
    let caps = g.caps();
    assert!(!caps.float_atomics, "wgpu on GL has no float atomics (its GLSL has no atomicAdd on floats)");
    let kernels: Vec<_> =
        flavors(&caps, false).into_iter().filter(|k| !k.shader_name().starts_with("hash_scatter")).collect();
    // 147 flavors with a bound on llvmpipe (2026-11-25): no `_f32`, `_sh` or `_tex`, every
    // other switch. At least 140, so that a whole family lost (every `_sto`, `_imm` or
    // `_cu` flavor: 20 or more each) fails here instead of passing on fewer.
    assert_kernels_match_twins(&mut g, &kernels, 64, 0x91, 140, "wgpu on GL");
}

#[test]
fn rollouts_on_wgpu_gl_stay_close_to_the_cpu() {
    for variant in [Variant::NAIVE, Variant::OPTIMIZED] {
        let Some(mut g) = on_gl(variant, 64) else { return };
        // 208 substeps; ROLLOUT_BOUND_PER_SUBSTEP × substeps, as every other backend.
        let c = validate_rollout(&mut g, 13).unwrap();
        assert_checks(&format!("{} on GL", g.name()), std::slice::from_ref(&c));
        // The optimized recipe is exact on llvmpipe, as on every other API there
        // (bit_identity.rs: dot3/len3 keep Mesa's GLSL path from fusing).
        if variant == Variant::OPTIMIZED && g.adapter().contains("llvmpipe") {
            assert_eq!(c.max_abs, 0.0, "{} on GL: the optimized rollout left the CPU's bits", g.name());
        }
    }
}

#[test]
fn the_wgpu_renderer_on_gl_draws_the_picture_it_draws_on_vulkan() {
    let Some(mut g) = on_gl(Variant::OPTIMIZED, 32) else { return };
    for _ in 0..60 {
        g.step_frame().unwrap();
    }
    let state = g.state().unwrap();
    let (_, topo) = clothlab_core::build(g.scene(), g.params()).unwrap();
    let ctx = g.engine().context();
    let (w, h) = (320, 240);
    let mut r = WgpuRenderer::new(ctx, g.scene(), &topo, w, h).unwrap();
    let (pos, normal) = g.vertex_buffers();
    r.render(ctx, &test_view(RenderMode::Triangles), ClothSource::Gpu { pos, normal }).unwrap();
    let on_gl = r.read_image(ctx).unwrap();
    let Some(vk) = or_skip(GpuContext::with_backends(wgpu::Backends::VULKAN), "wgpu on Vulkan") else { return };
    assert_eq!(vk.info.backend, wgpu::Backend::Vulkan);
    let mut rv = WgpuRenderer::new(&vk, g.scene(), &topo, w, h).unwrap();
    rv.render(&vk, &test_view(RenderMode::Triangles), ClothSource::Cpu(&state)).unwrap();
    let on_vk = rv.read_image(&vk).unwrap();
    let (mean, bad) = image_diff(&on_gl, &on_vk);
    println!("wgpu GL vs Vulkan: mean {mean:.3}/255, {:.3} % of pixels off by > 48", bad * 100.0);
    // The golden-image threshold of the renderer tests.
    assert!(mean <= 2.0 && bad <= 0.02, "wgpu's picture on GL differs from Vulkan's ({mean}, {bad})");
}

#[test]
fn a_raw_gl_solver_outlives_wgpu_gl_instances_made_and_dropped_beside_it() {
    // wgpu's GL backend terminates its EGL display when its last instance drops; raw GL's
    // contexts must not be on that display (clothlab-gl opens its own through
    // EGL_EXT_platform_device), or the raw solver's next call fails ("not a valid EGL
    // display"). Found by the free-fall test once wgpu was built with GL.
    let Some(mut raw) = or_skip(
        clothlab_gl::gl_solver(Variant::OPTIMIZED, Scene::with_n(24), SimParams::default(), SolverOptions::default()),
        "raw GL",
    ) else {
        return;
    };
    // The raw solver stays in step with the CPU while wgpu GL instances come and go
    // (validate_rollout steps both from the start, frame by frame).
    let mut frames = 0;
    for _ in 0..2 {
        let Some(mut w) = on_gl(Variant::NAIVE, 16) else { return };
        w.step_frame().unwrap();
        drop(w);
        raw.step_frame().unwrap();
        frames += 1;
    }
    let mut cpu =
        clothlab_cpu::CpuSolver::new(clothlab_cpu::Exec::Serial, raw.scene().clone(), raw.params().clone()).unwrap();
    for _ in 0..frames {
        cpu.step_frame().unwrap();
    }
    let mut c = clothlab_cpu::validate::compare("", "pos", &raw.state().unwrap().pos, &cpu.state_ref().pos, false, 0.0);
    // The rollout bound of every backend (1e-6 m per substep), over the 32 substeps.
    c.bound = clothlab_cpu::validate::ROLLOUT_BOUND_PER_SUBSTEP * 32.0;
    c.error = c.max_abs;
    assert_checks("raw GL after wgpu GL instances", &[c]);
}

/// A mesh (the flag: wind, pins, a hole) on wgpu's GL backend: every flavor that runs on
/// a mesh within its bound, and the optimized recipe's 8-frame rollout exactly the CPU
/// solver's on llvmpipe (tests/tests/suite/mesh_gpu.rs does the other three stacks).
#[test]
fn a_mesh_on_wgpu_gl_matches_its_twins_and_the_cpu_bit_for_bit() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let file = clothlab_core::SceneFile::load(&dir.join("mesh-flag.toml")).unwrap();
    let make = || gl_solver_of(Variant::OPTIMIZED, file.scene.clone(), file.params.clone());
    let Some(mut g) = make() else { return };
    let kernels: Vec<_> = flavors(&g.caps(), false).into_iter().collect();
    let checks =
        clothlab_engine::validate::validate_kernels_with(&mut g, &kernels, &file.scene, 0x3e5, &file.params).unwrap();
    assert!(checks.iter().any(|c| c.what == "xpbd_mesh"), "the mesh's XPBD pass was not compared");
    assert_checks("wgpu on GL, mesh", &checks);
    let mut fresh = make().unwrap();
    let c = validate_rollout(&mut fresh, 8).unwrap();
    println!("wgpu on GL, mesh: rollout {} max {:e}", c.what, c.max_abs);
    if fresh.adapter().contains("llvmpipe") {
        assert_eq!(c.max_abs, 0.0, "the optimized recipe on a mesh differs from the CPU solver");
    } else {
        assert_checks("wgpu on GL, mesh", &[c]);
    }
}
