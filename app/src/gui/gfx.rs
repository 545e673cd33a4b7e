//! The window's graphics on either API: the scene renderer of that API at window size,
//! egui over it, presentation, picking and screenshots.

use std::sync::Arc;

use anyhow::{Context, Result, bail};
use clothlab::core::{Scene, View};
use clothlab_gl::{GlContext, GlOverlay, GlRenderer};
use clothlab_vulkan::Device;
use clothlab_vulkan::{Overlay, Presenter, VulkanRenderer};
use clothlab_wgpu::{GpuContext, WgpuRenderer};
use winit::window::Window;

use clothlab::backend::Api;
use clothlab::backend::{AnySolver, Shared, gl_cloth, vulkan_cloth, wgpu_cloth};

/// A picture of the whole window (scene and panels), sRGB RGBA8.
pub struct Shot {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Rows, top first.
    pub rgba: Vec<u8>,
}

/// egui's output of a frame, for the API's egui renderer.
pub struct EguiFrame<'a> {
    /// Tessellated shapes.
    pub primitives: &'a [egui::ClippedPrimitive],
    /// Texture changes.
    pub textures: &'a egui::TexturesDelta,
    /// Pixels per point.
    pub pixels_per_point: f32,
}

/// wgpu: the surface, the scene renderer (drawn as an egui image behind the panels).
pub struct WgpuGfx {
    ctx: GpuContext,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    renderer: WgpuRenderer,
    egui: egui_wgpu::Renderer,
    scene_tex: egui::TextureId,
    capturable: bool,
}

/// Raw Vulkan: the scene renderer and the presenter (scene blitted, egui on top).
pub struct VulkanGfx {
    renderer: VulkanRenderer,
    presenter: Presenter,
    dev: Device,
}

/// Raw OpenGL: the window's context (GL solvers compute in it too), the scene renderer
/// (its picture blitted into the window) and egui over it.
pub struct GlGfx {
    renderer: GlRenderer,
    overlay: GlOverlay,
    ctx: GlContext,
    /// The window's drawable size.
    size: (u32, u32),
}

/// The window's graphics.
pub enum Gfx {
    /// Through wgpu.
    Wgpu(Box<WgpuGfx>),
    /// Through raw Vulkan.
    Vulkan(Box<VulkanGfx>),
    /// Through raw OpenGL.
    Gl(Box<GlGfx>),
    /// Nothing, for the moment of an API switch.
    None,
}

impl Gfx {
    /// No graphics (while switching APIs).
    pub fn new_placeholder() -> Self {
        Gfx::None
    }

    /// Graphics for `window` on `api`, drawing `scene` (its cloth topology built from
    /// `params`) at the window's size.
    pub fn new(api: Api, window: &Arc<Window>, scene: &Scene, params: &clothlab::core::SimParams) -> Result<Self> {
        let size = window.inner_size();
        let (w, h) = (size.width.max(1), size.height.max(1));
        let (_, topo) = clothlab::core::build(scene, params)?;
        Ok(match api {
            Api::Gl => {
                let ctx = GlContext::for_window(window.clone())?;
                let renderer = GlRenderer::new(&ctx, scene, &topo, w, h)?;
                let overlay = GlOverlay::new(&ctx)?;
                Gfx::Gl(Box::new(GlGfx { renderer, overlay, ctx, size: (w, h) }))
            }
            Api::Wgpu => {
                let (ctx, surface) = GpuContext::for_window(window.clone())?;
                let caps = surface.get_capabilities(&ctx.adapter);
                // egui-wgpu wants a non-sRGB target (it writes gamma-encoded colours, and
                // samples the sRGB scene image to linear and encodes it again).
                let format = caps
                    .formats
                    .iter()
                    .copied()
                    .find(|f| matches!(f, wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm))
                    .or(caps.formats.first().copied())
                    .context("the window surface offers no format")?;
                let capturable = caps.usages.contains(wgpu::TextureUsages::COPY_SRC);
                let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
                if capturable {
                    usage |= wgpu::TextureUsages::COPY_SRC;
                }
                let mut config = surface
                    .get_default_config(&ctx.adapter, w, h)
                    .context("the window surface does not work with this adapter")?;
                config.format = format;
                config.usage = usage;
                config.present_mode = wgpu::PresentMode::AutoVsync;
                config.desired_maximum_frame_latency = 2;
                surface.configure(&ctx.device, &config);
                let renderer = WgpuRenderer::new(&ctx, scene, &topo, w, h)?;
                let mut egui = egui_wgpu::Renderer::new(&ctx.device, format, egui_wgpu::RendererOptions::default());
                let scene_tex =
                    egui.register_native_texture(&ctx.device, renderer.color_view(), wgpu::FilterMode::Linear);
                Gfx::Wgpu(Box::new(WgpuGfx { ctx, surface, config, renderer, egui, scene_tex, capturable }))
            }
            Api::Vulkan => {
                let dev = Device::for_window(clothlab::backend::vulkan_validation(), window.as_ref())?;
                let renderer = VulkanRenderer::new(&dev, scene, &topo, w, h)?;
                let presenter = Presenter::new(&dev, w, h)?;
                Gfx::Vulkan(Box::new(VulkanGfx { renderer, presenter, dev }))
            }
        })
    }

    /// The device GPU solvers share with the renderer.
    pub fn shared(&self) -> Shared<'_> {
        match self {
            Gfx::Wgpu(g) => Shared::Wgpu(&g.ctx),
            Gfx::Vulkan(g) => Shared::Vulkan(&g.dev),
            Gfx::Gl(g) => Shared::Gl(&g.ctx),
            Gfx::None => Shared::None,
        }
    }

    /// Which API draws.
    pub fn api(&self) -> Api {
        match self {
            Gfx::Wgpu(_) => Api::Wgpu,
            Gfx::Gl(_) => Api::Gl,
            Gfx::Vulkan(_) | Gfx::None => Api::Vulkan,
        }
    }

    /// One line naming the adapter.
    pub fn adapter(&self) -> String {
        match self {
            Gfx::Wgpu(g) => g.ctx.describe(),
            Gfx::Vulkan(g) => format!("{} (raw Vulkan)", g.dev.name()),
            Gfx::Gl(g) => format!("{} (raw OpenGL)", g.ctx.adapter()),
            Gfx::None => String::new(),
        }
    }

    /// The scene image for egui to paint behind the panels (wgpu), or `None` when the
    /// presenter puts the scene under egui itself (Vulkan).
    pub fn scene_texture(&self) -> Option<egui::TextureId> {
        match self {
            Gfx::Wgpu(g) => Some(g.scene_tex),
            Gfx::Vulkan(_) | Gfx::Gl(_) | Gfx::None => None,
        }
    }

    /// A new cloth topology (the grid size changed): the renderer is made anew.
    pub fn rebuild(&mut self, scene: &Scene, params: &clothlab::core::SimParams) -> Result<()> {
        let (_, topo) = clothlab::core::build(scene, params)?;
        match self {
            Gfx::Wgpu(g) => {
                let (w, h) = g.renderer.size();
                g.renderer = WgpuRenderer::new(&g.ctx, scene, &topo, w, h)?;
                g.egui.update_egui_texture_from_wgpu_texture(
                    &g.ctx.device,
                    g.renderer.color_view(),
                    wgpu::FilterMode::Linear,
                    g.scene_tex,
                );
            }
            Gfx::Vulkan(g) => {
                let (w, h) = g.renderer.size();
                g.dev.wait_idle()?;
                g.renderer = VulkanRenderer::new(&g.dev, scene, &topo, w, h)?;
            }
            Gfx::Gl(g) => {
                let (w, h) = g.renderer.size();
                g.renderer = GlRenderer::new(&g.ctx, scene, &topo, w, h)?;
            }
            Gfx::None => {}
        }
        Ok(())
    }

    /// The window's drawable size changed (zero when minimised).
    pub fn resize(&mut self, width: u32, height: u32) -> Result<()> {
        match self {
            Gfx::Wgpu(g) => {
                if width == 0 || height == 0 {
                    return Ok(());
                }
                g.config.width = width;
                g.config.height = height;
                g.surface.configure(&g.ctx.device, &g.config);
                g.renderer.resize(&g.ctx, width, height)?;
                g.egui.update_egui_texture_from_wgpu_texture(
                    &g.ctx.device,
                    g.renderer.color_view(),
                    wgpu::FilterMode::Linear,
                    g.scene_tex,
                );
            }
            Gfx::Vulkan(g) => g.presenter.resize(width, height),
            Gfx::Gl(g) => {
                g.size = (width, height);
                if width > 0 && height > 0 {
                    g.renderer.resize(&g.ctx, width, height)?;
                }
            }
            Gfx::None => {}
        }
        Ok(())
    }

    /// The scene's size in pixels.
    pub fn scene_size(&self) -> (u32, u32) {
        match self {
            Gfx::Wgpu(g) => g.renderer.size(),
            Gfx::Vulkan(g) => g.renderer.size(),
            Gfx::Gl(g) => g.renderer.size(),
            Gfx::None => (1, 1),
        }
    }

    /// Moves the drawn colliders to where the solver's have them now (moving colliders
    /// only; still ones stay as the renderer was made with them).
    fn follow_colliders(&mut self, solver: &AnySolver) -> Result<()> {
        let s = solver.get_ref();
        if !s.scene().moves() {
            return Ok(());
        }
        let now = s.scene().moved_to(s.time());
        match self {
            Gfx::Wgpu(g) => g.renderer.set_colliders(&g.ctx, &now)?,
            Gfx::Vulkan(g) => g.renderer.set_colliders(&now)?,
            Gfx::Gl(g) => g.renderer.set_colliders(&g.ctx, &now)?,
            Gfx::None => {}
        }
        Ok(())
    }

    /// The particle under pixel `(x, y)` of the scene, if any.
    pub fn pick(&mut self, solver: &mut AnySolver, view: &View, x: u32, y: u32) -> Result<Option<u32>> {
        self.follow_colliders(solver)?;
        let mut copy = None;
        Ok(match self {
            Gfx::Wgpu(g) => {
                let cloth = wgpu_cloth(solver, &mut copy)?;
                g.renderer.pick(&g.ctx, view, cloth, x, y)?
            }
            Gfx::Vulkan(g) => {
                g.dev.wait_idle()?;
                let cloth = vulkan_cloth(solver, &mut copy)?;
                g.renderer.pick(view, cloth, x, y)?
            }
            Gfx::Gl(g) => {
                let cloth = gl_cloth(solver, &mut copy, &g.ctx)?;
                g.renderer.pick(&g.ctx, view, cloth, x, y)?
            }
            Gfx::None => None,
        })
    }

    /// The 3-D view alone (File → Save image), as rendered last.
    pub fn scene_image(&mut self, solver: &mut AnySolver, view: &View) -> Result<Shot> {
        self.follow_colliders(solver)?;
        let mut copy = None;
        let (width, height) = self.scene_size();
        let rgba = match self {
            Gfx::Wgpu(g) => {
                let cloth = wgpu_cloth(solver, &mut copy)?;
                g.renderer.render(&g.ctx, view, cloth)?;
                g.renderer.read_image(&g.ctx)?
            }
            Gfx::Vulkan(g) => {
                g.dev.wait_idle()?;
                let cloth = vulkan_cloth(solver, &mut copy)?;
                g.renderer.render(view, cloth)?;
                g.renderer.read_image()?
            }
            Gfx::Gl(g) => {
                let cloth = gl_cloth(solver, &mut copy, &g.ctx)?;
                g.renderer.render(&g.ctx, view, cloth)?;
                g.renderer.read_image(&g.ctx)?
            }
            Gfx::None => bail!("no graphics"),
        };
        Ok(Shot { width, height, rgba })
    }

    /// Draws the scene and egui and presents; with `capture`, returns what the window
    /// shows.
    pub fn draw(
        &mut self,
        solver: &mut AnySolver,
        view: &View,
        egui: EguiFrame<'_>,
        capture: bool,
    ) -> Result<Option<Shot>> {
        self.follow_colliders(solver)?;
        let mut copy = None;
        match self {
            Gfx::Wgpu(g) => {
                if g.config.width == 0 || g.config.height == 0 {
                    return Ok(None);
                }
                let cloth = wgpu_cloth(solver, &mut copy)?;
                g.renderer.render(&g.ctx, view, cloth)?;
                g.draw_egui(egui, capture)
            }
            Gfx::Vulkan(g) => {
                let cloth = vulkan_cloth(solver, &mut copy)?;
                if capture {
                    g.presenter.request_screenshot();
                }
                let overlay = Overlay {
                    primitives: egui.primitives,
                    pixels_per_point: egui.pixels_per_point,
                    textures: egui.textures,
                };
                g.presenter.draw(&mut g.renderer, view, cloth, Some(overlay))?;
                if !capture {
                    return Ok(None);
                }
                Ok(g.presenter.take_screenshot()?.map(|s| Shot { width: s.width, height: s.height, rgba: s.rgba }))
            }
            Gfx::Gl(g) => {
                let (w, h) = g.size;
                if w == 0 || h == 0 {
                    return Ok(None);
                }
                let cloth = gl_cloth(solver, &mut copy, &g.ctx)?;
                g.renderer.render(&g.ctx, view, cloth)?;
                // The scene under the panels, as on Vulkan: blitted into the window.
                g.renderer.present(&g.ctx, w, h)?;
                g.overlay.paint([w, h], egui.pixels_per_point, egui.primitives, egui.textures)?;
                let shot =
                    if capture { Some(Shot { width: w, height: h, rgba: g.ctx.read_window(w, h)? }) } else { None };
                g.ctx.swap_buffers()?;
                Ok(shot)
            }
            Gfx::None => Ok(None),
        }
    }
}

impl WgpuGfx {
    fn draw_egui(&mut self, e: EguiFrame<'_>, capture: bool) -> Result<Option<Shot>> {
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f) | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&self.ctx.device, &self.config);
                return Ok(None);
            }
            other => {
                log::warn!("no surface texture this frame: {other:?}");
                return Ok(None);
            }
        };
        let view = frame.texture.create_view(&Default::default());
        let dev = &self.ctx.device;
        for (id, deltas) in &e.textures.set {
            for delta in deltas {
                self.egui.update_texture(dev, &self.ctx.queue, *id, delta);
            }
        }
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [self.config.width, self.config.height],
            pixels_per_point: e.pixels_per_point,
        };
        let mut enc = dev.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("egui") });
        let extra = self.egui.update_buffers(dev, &self.ctx.queue, &mut enc, e.primitives, &screen);
        let (w, h) = (self.config.width, self.config.height);
        // A surface that cannot be copied (wgpu on GL): the screenshot frame is drawn a
        // second time into a texture of the surface's format that can be.
        let offscreen = (capture && !self.capturable).then(|| {
            dev.create_texture(&wgpu::TextureDescriptor {
                label: Some("screenshot target"),
                size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: self.config.format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        });
        let offscreen_view = offscreen.as_ref().map(|t| t.create_view(&Default::default()));
        for target in std::iter::once(&view).chain(offscreen_view.as_ref()) {
            let pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("egui"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let mut pass = pass.forget_lifetime();
            self.egui.render(&mut pass, e.primitives, &screen);
        }
        let row = (w as u64 * 4).div_ceil(256) * 256;
        let readback = capture.then(|| {
            let buf = dev.create_buffer(&wgpu::BufferDescriptor {
                label: Some("screenshot"),
                size: row * h as u64,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            enc.copy_texture_to_buffer(
                offscreen.as_ref().unwrap_or(&frame.texture).as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer: &buf,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(row as u32),
                        rows_per_image: None,
                    },
                },
                wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
            );
            buf
        });
        self.ctx.queue.submit(extra.into_iter().chain([enc.finish()]));
        self.ctx.queue.present(frame);
        for id in &e.textures.free {
            self.egui.free_texture(id);
        }
        self.ctx.check("drawing the window")?;
        let Some(buf) = readback else { return Ok(None) };
        let raw = self.ctx.read_buffer(&buf, 0, buf.size())?;
        let mut rgba: Vec<u8> = raw.chunks(row as usize).flat_map(|r| r[..w as usize * 4].iter().copied()).collect();
        if matches!(self.config.format, wgpu::TextureFormat::Bgra8UnormSrgb | wgpu::TextureFormat::Bgra8Unorm) {
            rgba.chunks_exact_mut(4).for_each(|p| p.swap(0, 2));
        }
        Ok(Some(Shot { width: w, height: h, rgba }))
    }
}
