//! The Vulkan presenter on a real window (X11; CI runs the suite under Xvfb): the scene and
//! an egui overlay reach the swapchain, a resize makes a new swapchain of the new size,
//! and nothing draws a validation-layer message.

use std::time::Duration;

use clothlab_core::{OrbitCamera, RenderMode, Scene, SimParams, Solver, View};
use clothlab_engine::Variant;
use clothlab_vulkan::{
    Device, GpuSolver, Overlay, Presented, Presenter, SolverOptions, VkCloth, VulkanEngine, VulkanRenderer,
    VulkanSolver,
};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::platform::pump_events::EventLoopExtPumpEvents;
use winit::platform::x11::EventLoopBuilderExtX11;
use winit::window::{Window, WindowId};

/// Whether a missing display fails the test (CI sets it and runs under Xvfb).
fn display_required() -> bool {
    std::env::var("CLOTHLAB_REQUIRE_DISPLAY").is_ok_and(|v| v == "1")
}

#[derive(Default)]
struct App {
    window: Option<Window>,
    size: Option<PhysicalSize<u32>>,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_none() {
            let attrs = Window::default_attributes()
                .with_title("clothlab window test")
                .with_inner_size(PhysicalSize::new(320, 240));
            self.window = Some(event_loop.create_window(attrs).expect("a window on the display"));
        }
    }

    fn window_event(&mut self, _: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        if let WindowEvent::Resized(size) = event {
            self.size = Some(size);
        }
    }
}

fn pump(event_loop: &mut EventLoop<()>, app: &mut App) {
    for _ in 0..5 {
        let _ = event_loop.pump_app_events(Some(Duration::from_millis(20)), app);
    }
}

#[test]
fn frames_with_an_egui_overlay_reach_the_swapchain_across_a_resize() {
    if std::env::var_os("DISPLAY").is_none() && std::env::var_os("WAYLAND_DISPLAY").is_none() {
        assert!(!display_required(), "CLOTHLAB_REQUIRE_DISPLAY=1 but no DISPLAY: run under xvfb-run");
        eprintln!("skipped: no display (run under xvfb-run)");
        return;
    }
    let mut event_loop = match EventLoop::builder().with_any_thread(true).build() {
        Ok(e) => e,
        Err(e) => {
            assert!(!display_required(), "no event loop: {e}");
            eprintln!("skipped: {e}");
            return;
        }
    };
    let mut app = App::default();
    pump(&mut event_loop, &mut app);
    let window = app.window.take().expect("resumed creates the window");
    let dev = Device::for_window(true, &window).expect("a Vulkan device presenting to the window");
    let scene = Scene::with_n(24);
    let params = SimParams::default();
    let engine = VulkanEngine::on_device(&dev).unwrap();
    let mut solver =
        GpuSolver::new(engine, Variant::OPTIMIZED, scene.clone(), params.clone(), SolverOptions::default()).unwrap();
    let (_, topo) = clothlab_core::build(&scene, &params).unwrap();
    let size = window.inner_size();
    let mut renderer = VulkanRenderer::new(&dev, &scene, &topo, size.width, size.height).unwrap();
    let mut presenter = Presenter::new(&dev, size.width, size.height).unwrap();
    let egui_ctx = egui::Context::default();
    let view = View { camera: OrbitCamera::default(), light: [2.0, 5.5, 3.0], mode: RenderMode::Triangles };

    let mut frames = 0;
    let drawn_primitives = std::cell::Cell::new(0usize);
    let mut draw = |presenter: &mut Presenter, solver: &mut VulkanSolver, w: u32, h: u32| {
        solver.step_frame().unwrap();
        let input = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(w as f32, h as f32))),
            ..Default::default()
        };
        let out = egui_ctx.run_ui(input, |ui| {
            egui::Window::new("overlay").show(ui.ctx(), |ui| ui.label("egui over the cloth"));
        });
        let primitives = egui_ctx.tessellate(out.shapes, out.pixels_per_point);
        // egui lays windows out in a first, invisible pass: shapes come from frame two.
        drawn_primitives.set(drawn_primitives.get() + primitives.len());
        let (pos, normal) = solver.vertex_buffers();
        let overlay =
            Overlay { primitives: &primitives, pixels_per_point: out.pixels_per_point, textures: &out.textures_delta };
        presenter.draw(&mut renderer, &view, VkCloth::Gpu { pos, normal }, Some(overlay)).unwrap()
    };
    for _ in 0..12 {
        if draw(&mut presenter, &mut solver, size.width, size.height) == Presented::Frame {
            frames += 1;
        }
    }
    assert!(frames >= 10, "{frames} of 12 frames presented");
    assert!(drawn_primitives.get() > 0, "egui drew nothing");
    assert_eq!(presenter.extent(), Some((size.width, size.height)));

    // A resize: the next frame makes a swapchain of the new size (an out-of-date
    // swapchain may skip one frame).
    let _ = window.request_inner_size(PhysicalSize::new(400, 300));
    app.window = Some(window);
    pump(&mut event_loop, &mut app);
    let window = app.window.take().unwrap();
    let new = window.inner_size();
    assert_eq!((new.width, new.height), (400, 300), "Xvfb applies the size");
    presenter.resize(new.width, new.height);
    let mut after = 0;
    for _ in 0..8 {
        if draw(&mut presenter, &mut solver, new.width, new.height) == Presented::Frame {
            after += 1;
        }
    }
    assert!(after >= 6, "{after} of 8 frames presented after the resize");
    // A screenshot of the window: the scene's sky and the egui window are there.
    presenter.request_screenshot();
    draw(&mut presenter, &mut solver, new.width, new.height);
    let shot = presenter.take_screenshot().unwrap().expect("lavapipe swapchains allow TRANSFER_SRC");
    assert_eq!((shot.width, shot.height), (400, 300));
    if let Ok(path) = std::env::var("CLOTHLAB_SCREENSHOT") {
        image::save_buffer(&path, &shot.rgba, shot.width, shot.height, image::ExtendedColorType::Rgba8).unwrap();
    }
    // Sky (0.62, 0.72, 0.85 linear → about (206, 221, 238) in sRGB) in the top right corner,
    // far from the egui window (top left).
    let px = |x: u32, y: u32| &shot.rgba[((y * shot.width + x) * 4) as usize..][..3];
    let sky = px(395, 5);
    assert!(sky[2] > 220 && sky[0] > 190 && sky[0] < 220, "sky pixel {sky:?}");
    // egui's default dark window fill near its top left corner.
    let panel = px(20, 30);
    assert!(panel.iter().all(|&c| c < 90), "egui window pixel {panel:?}");
    assert_eq!(presenter.extent(), Some((400, 300)));
    assert!(presenter.swapchains_made >= 2, "a new swapchain for the new size");
    assert_eq!(renderer.size(), (400, 300), "the scene follows the swapchain");
    // Teardown in reverse order, with the validation layer watching.
    drop(presenter);
    drop(renderer);
    let m = solver.engine().take_validation_messages();
    assert!(m.is_empty(), "validation layer: {m:#?}");
    drop(solver);
    drop(dev);
    drop(window);
}
