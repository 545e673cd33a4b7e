//! The Vulkan renderer against the wgpu renderer: the same cloth state drawn by both must
//! give the same picture in every mode, picking must find the same particle, and nothing
//! may draw a validation-layer message (synchronization validation on).

use clothlab_core::grid::ClothState;
use clothlab_core::{RenderMode, Scene, SimParams, Solver, View};
use clothlab_engine::Variant;
use clothlab_tests::{image_diff, or_skip, test_view};
use clothlab_vulkan::{SolverOptions, VkCloth, VulkanRenderer, VulkanSolver, vulkan_solver};
use clothlab_wgpu::{ClothSource, GpuContext, WgpuRenderer};

const W: u32 = 320;
const H: u32 = 240;
const N: u32 = 32;
const FRAMES: u32 = 60;

fn view(mode: RenderMode) -> View {
    test_view(mode)
}

/// The optimized Vulkan solver after `FRAMES` frames (validation on), or `None` without
/// an adapter.
fn simulated() -> Option<VulkanSolver> {
    let options = SolverOptions::default();
    let mut s = or_skip(
        vulkan_solver(Variant::OPTIMIZED, Scene::with_n(N), SimParams::default(), true, options),
        "vulkan solver",
    )?;
    for _ in 0..FRAMES {
        s.step_frame().unwrap();
    }
    Some(s)
}

fn vulkan_renderer(s: &VulkanSolver) -> VulkanRenderer {
    let (_, topo) = clothlab_core::build(s.scene(), s.params()).unwrap();
    VulkanRenderer::new(&s.engine().device(), s.scene(), &topo, W, H).unwrap()
}

/// The wgpu renderer's picture of `state`.
fn wgpu_picture(state: &ClothState, scene: &Scene, mode: RenderMode) -> Vec<u8> {
    let ctx = GpuContext::new().unwrap();
    let (_, topo) = clothlab_core::build(scene, &SimParams::default()).unwrap();
    let mut r = WgpuRenderer::new(&ctx, scene, &topo, W, H).unwrap();
    r.render(&ctx, &view(mode), ClothSource::Cpu(state)).unwrap();
    r.read_image(&ctx).unwrap()
}

fn no_validation_messages(s: &VulkanSolver) {
    let m = s.engine().take_validation_messages();
    assert!(m.is_empty(), "validation layer: {m:#?}");
}

#[test]
fn vulkan_pictures_match_the_wgpu_renderer_in_every_mode() {
    let Some(mut s) = simulated() else { return };
    let state = s.state().unwrap();
    let mut r = vulkan_renderer(&s);
    for mode in [RenderMode::Triangles, RenderMode::Lines, RenderMode::Points] {
        let (pos, normal) = s.vertex_buffers();
        r.render(&view(mode), VkCloth::Gpu { pos, normal }).unwrap();
        let vk_img = r.read_image().unwrap();
        let wgpu_img = wgpu_picture(&state, s.scene(), mode);
        let (mean, bad) = image_diff(&vk_img, &wgpu_img);
        println!("{mode:?}: mean {mean:.3}/255, {:.3} % of pixels off by > 48", bad * 100.0);
        if mean > 2.0 || bad > 0.02 {
            let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
            image::save_buffer(dir.join(format!("vk-{mode:?}.png")), &vk_img, W, H, image::ExtendedColorType::Rgba8)
                .unwrap();
            image::save_buffer(
                dir.join(format!("wgpu-{mode:?}.png")),
                &wgpu_img,
                W,
                H,
                image::ExtendedColorType::Rgba8,
            )
            .unwrap();
        }
        // The golden-image threshold: rasterisation rules leave room for edge pixels only.
        assert!(mean <= 2.0 && bad <= 0.02, "{mode:?}: Vulkan and wgpu pictures differ ({mean}, {bad})");
    }
    no_validation_messages(&s);
}

#[test]
fn the_vulkan_renderer_draws_a_cpu_state_like_the_solver_buffers() {
    // The CPU upload path (host-visible vertex buffers) and the no-copy path draw the same
    // state: the pictures must agree to the byte.
    let Some(mut s) = simulated() else { return };
    let state = s.state().unwrap();
    let mut r = vulkan_renderer(&s);
    let (pos, normal) = s.vertex_buffers();
    r.render(&view(RenderMode::Triangles), VkCloth::Gpu { pos, normal }).unwrap();
    let gpu = r.read_image().unwrap();
    r.render(&view(RenderMode::Triangles), VkCloth::Cpu(&state)).unwrap();
    let cpu = r.read_image().unwrap();
    assert_eq!(image_diff(&gpu, &cpu), (0.0, 0.0));
    no_validation_messages(&s);
}

#[test]
fn vulkan_picking_finds_the_same_particle_as_wgpu() {
    let Some(mut s) = simulated() else { return };
    let state = s.state().unwrap();
    let mut r = vulkan_renderer(&s);
    let ctx = GpuContext::new().unwrap();
    let (_, topo) = clothlab_core::build(s.scene(), s.params()).unwrap();
    let mut w = WgpuRenderer::new(&ctx, s.scene(), &topo, W, H).unwrap();
    let v = view(RenderMode::Triangles);
    let mut hits = 0;
    for (x, y) in [(160, 80), (150, 100), (170, 110), (140, 60), (5, 230), (300, 10)] {
        let (pos, normal) = s.vertex_buffers();
        let _ = normal;
        let a = r.pick(&v, VkCloth::Gpu { pos, normal }, x, y).unwrap();
        let b = w.pick(&ctx, &v, ClothSource::Cpu(&state), x, y).unwrap();
        assert_eq!(a, b, "pixel ({x}, {y})");
        hits += a.is_some() as u32;
    }
    assert!(hits >= 2, "the probes should hit the cloth at least twice, hit {hits}");
    assert_eq!(r.pick(&v, VkCloth::Cpu(&state), W, 0).unwrap(), None, "outside the target");
    no_validation_messages(&s);
}

#[test]
fn resizing_and_bad_sizes_leave_no_validation_messages() {
    let Some(mut s) = simulated() else { return };
    let mut r = vulkan_renderer(&s);
    assert!(r.resize(0, 10).is_err(), "zero width refused");
    assert!(r.resize(10, 1 << 20).is_err(), "oversized height refused");
    assert_eq!(r.size(), (W, H), "a refused size changes nothing");
    r.resize(1, 1).unwrap();
    let (pos, normal) = s.vertex_buffers();
    r.render(&view(RenderMode::Points), VkCloth::Gpu { pos, normal }).unwrap();
    assert_eq!(r.read_image().unwrap().len(), 4);
    r.resize(W, H).unwrap();
    let (pos, normal) = s.vertex_buffers();
    r.render(&view(RenderMode::Triangles), VkCloth::Gpu { pos, normal }).unwrap();
    assert_eq!(r.read_image().unwrap().len(), (W * H * 4) as usize);
    drop(r);
    s.step_frame().unwrap();
    no_validation_messages(&s);
}
