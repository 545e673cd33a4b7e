//! Putting frames on a window: a swapchain on the device's surface, two frames in flight
//! (a fence and an acquire semaphore per frame slot, a render-finished semaphore per
//! swapchain image), the scene from [`VulkanRenderer`] blitted onto the swapchain image,
//! and egui drawn over it by egui-ash-renderer. A resized, minimised (zero extent) or
//! out-of-date surface makes a new swapchain on the next frame; nothing is drawn while
//! the extent is zero.

use std::sync::Arc;

use ash::vk;
use clothlab_core::solver::{RenderError, View};
use egui_ash_renderer::allocator::DefaultAllocator;
use egui_ash_renderer::{DynamicRendering, Options, RenderMode};

use crate::VkError;
use crate::raw::{Acquired, Buffer, Commands, Device, Semaphore, Swapchain, Transition};
use crate::render::{FRAMES_IN_FLIGHT, VkCloth, VulkanRenderer};
use gpu_allocator::MemoryLocation;

fn rerr(e: VkError) -> RenderError {
    RenderError::Backend(e.to_string())
}

fn eerr(e: egui_ash_renderer::RendererError) -> RenderError {
    RenderError::Backend(format!("egui renderer: {e}"))
}

/// egui's output for one frame.
pub struct Overlay<'a> {
    /// Tessellated shapes (`egui::Context::tessellate`).
    pub primitives: &'a [egui::ClippedPrimitive],
    /// Physical pixels per egui point.
    pub pixels_per_point: f32,
    /// Texture changes of the frame (`egui::FullOutput::textures_delta`).
    pub textures: &'a egui::TexturesDelta,
}

struct Slot {
    cmds: Commands,
    acquired: Semaphore,
    pending: bool,
    /// A copy of what this slot's frame showed, when a capture was asked for.
    capture: Option<(Buffer, vk::Extent2D)>,
}

/// A screenshot: what the window showed, as tightly packed sRGB RGBA8 rows.
pub struct Screenshot {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// The pixels.
    pub rgba: Vec<u8>,
}

/// What [`Presenter::draw`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Presented {
    /// A frame is on its way to the screen.
    Frame,
    /// Nothing drawn: the window has zero extent (minimised) or the swapchain was out of
    /// date and is made anew on the next call.
    Skipped,
}

/// A window's swapchain and the per-frame objects that feed it.
pub struct Presenter {
    egui: egui_ash_renderer::Renderer<DefaultAllocator>,
    swapchain: Option<Swapchain>,
    stale: bool,
    done: Vec<Semaphore>,
    slots: Vec<Slot>,
    frame: usize,
    size: (u32, u32),
    /// Frames presented so far.
    pub presented: u64,
    capture_next: bool,
    captured: Option<Screenshot>,
    /// Swapchains made so far (the first one included).
    pub swapchains_made: u32,
    dev: Arc<Device>,
}

impl Presenter {
    /// A presenter for the window the device was opened for ([`crate::Device::for_window`]),
    /// whose drawable size is `width × height` pixels.
    pub fn new(dev: &crate::Device, width: u32, height: u32) -> Result<Self, RenderError> {
        let dev = dev.raw();
        if dev.swapchain_loader.is_none() || !dev.dynamic_rendering {
            return Err(RenderError::Backend(format!(
                "{} cannot present: the device was not opened for a window, or lacks dynamic rendering",
                dev.name
            )));
        }
        let swapchain = Swapchain::new(dev, width, height, None).map_err(rerr)?;
        let format = swapchain.as_ref().map_or(vk::Format::B8G8R8A8_SRGB, |s| s.format);
        let egui = egui_ash_renderer::Renderer::with_default_allocator(
            dev.instance(),
            dev.physical,
            dev.device.clone(),
            RenderMode::DynamicRendering(DynamicRendering {
                color_attachment_format: format,
                depth_attachment_format: None,
                stencil_attachment_format: None,
            }),
            Options {
                in_flight_frames: FRAMES_IN_FLIGHT,
                enable_depth_test: false,
                enable_depth_write: false,
                srgb_framebuffer: is_srgb(format),
            },
        )
        .map_err(eerr)?;
        let mut slots = Vec::new();
        for _ in 0..FRAMES_IN_FLIGHT {
            slots.push(Slot {
                cmds: Commands::new(dev, 0).map_err(rerr)?,
                acquired: Semaphore::new(dev).map_err(rerr)?,
                pending: false,
                capture: None,
            });
        }
        let mut me = Self {
            egui,
            swapchain: None,
            stale: false,
            done: Vec::new(),
            slots,
            frame: 0,
            size: (width, height),
            presented: 0,
            capture_next: false,
            captured: None,
            swapchains_made: 0,
            dev: dev.clone(),
        };
        me.adopt(swapchain)?;
        Ok(me)
    }

    fn adopt(&mut self, swapchain: Option<Swapchain>) -> Result<(), RenderError> {
        if let Some(s) = &swapchain {
            self.swapchains_made += 1;
            while self.done.len() < s.images.len() {
                self.done.push(Semaphore::new(&self.dev).map_err(rerr)?);
            }
            self.egui
                .set_render_mode(RenderMode::DynamicRendering(DynamicRendering {
                    color_attachment_format: s.format,
                    depth_attachment_format: None,
                    stencil_attachment_format: None,
                }))
                .map_err(eerr)?;
        }
        self.swapchain = swapchain;
        self.stale = false;
        Ok(())
    }

    /// The window's drawable size changed (zero when minimised): the next frame makes a
    /// new swapchain.
    pub fn resize(&mut self, width: u32, height: u32) {
        if (width, height) != self.size {
            self.size = (width, height);
            self.stale = true;
        }
    }

    /// The swapchain's size, `None` while nothing can be presented.
    pub fn extent(&self) -> Option<(u32, u32)> {
        self.swapchain.as_ref().map(|s| (s.extent.width, s.extent.height))
    }

    /// Copies the next presented frame (scene and egui) for [`Presenter::take_screenshot`].
    pub fn request_screenshot(&mut self) {
        self.capture_next = true;
    }

    /// The frame captured after [`Presenter::request_screenshot`], once it is complete.
    pub fn take_screenshot(&mut self) -> Result<Option<Screenshot>, RenderError> {
        self.settle()?;
        Ok(self.captured.take())
    }

    /// Waits for slot `k`'s frame and keeps its capture.
    fn finish(&mut self, k: usize) -> Result<(), RenderError> {
        let format = self.swapchain.as_ref().map(|s| s.format);
        let slot = &mut self.slots[k];
        if !slot.pending {
            return Ok(());
        }
        slot.cmds.wait(0).map_err(rerr)?;
        slot.pending = false;
        if let Some((buf, extent)) = slot.capture.take() {
            let mut rgba = buf.bytes().ok_or_else(|| RenderError::Backend("capture not host visible".into()))?.to_vec();
            if format == Some(vk::Format::B8G8R8A8_SRGB) || format == Some(vk::Format::B8G8R8A8_UNORM) {
                rgba.chunks_exact_mut(4).for_each(|p| p.swap(0, 2));
            }
            self.captured = Some(Screenshot { width: extent.width, height: extent.height, rgba });
        }
        Ok(())
    }

    /// Waits for every frame in flight.
    fn settle(&mut self) -> Result<(), RenderError> {
        for k in 0..self.slots.len() {
            self.finish(k)?;
        }
        self.dev.wait_idle().map_err(rerr)
    }

    /// Draws the scene of `renderer` (resized to the swapchain when needed) with `cloth`,
    /// egui's `overlay` over it, and presents it.
    pub fn draw(
        &mut self,
        renderer: &mut VulkanRenderer,
        view: &View,
        cloth: VkCloth<'_>,
        overlay: Option<Overlay<'_>>,
    ) -> Result<Presented, RenderError> {
        if self.stale || self.swapchain.is_none() {
            self.settle()?;
            let old = self.swapchain.take();
            let new = Swapchain::new(&self.dev, self.size.0, self.size.1, old.as_ref()).map_err(rerr)?;
            drop(old);
            self.adopt(new)?;
        }
        let Some(extent) = self.swapchain.as_ref().map(|s| s.extent) else {
            return Ok(Presented::Skipped);
        };
        if renderer.size() != (extent.width, extent.height) {
            // The targets are shared by the frames in flight: resize when none is.
            self.settle()?;
            renderer.resize(extent.width, extent.height)?;
        }
        let k = self.frame % FRAMES_IN_FLIGHT;
        self.finish(k)?;
        if let Some(o) = &overlay {
            // egui 0.36 may send several deltas for one texture in a frame: in order.
            for (id, deltas) in &o.textures.set {
                for delta in deltas {
                    let pool = self.slots[k].cmds.pool();
                    self.egui.set_texture(self.dev.queue, pool, *id, delta).map_err(eerr)?;
                }
            }
        }
        let swapchain = self.swapchain.as_ref().expect("checked above");
        let index = match swapchain.acquire(&self.slots[k].acquired).map_err(rerr)? {
            Acquired::OutOfDate => {
                self.stale = true;
                return Ok(Presented::Skipped);
            }
            Acquired::Image { index, suboptimal } => {
                self.stale |= suboptimal;
                index
            }
        };
        renderer.prepare(k, view, &cloth)?;
        let capture = if std::mem::take(&mut self.capture_next) && swapchain.capturable {
            let size = extent.width as u64 * extent.height as u64 * 4;
            let buf = Buffer::new(
                &self.dev,
                "screenshot",
                size,
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
            )
            .map_err(rerr)?;
            Some((buf, extent))
        } else {
            None
        };
        let slot = &mut self.slots[k];
        slot.cmds.begin(0).map_err(rerr)?;
        let c = &slot.cmds;
        VulkanRenderer::record_inputs_barrier(c);
        renderer.record(c, k, view, &cloth);
        use vk::AccessFlags as A;
        use vk::ImageLayout as L;
        use vk::PipelineStageFlags as P;
        c.transition_swapchain(
            swapchain,
            index,
            Transition {
                old: L::UNDEFINED,
                new: L::TRANSFER_DST_OPTIMAL,
                src_stage: P::TRANSFER,
                src_access: A::empty(),
                dst_stage: P::TRANSFER,
                dst_access: A::TRANSFER_WRITE,
            },
        );
        c.blit_to_swapchain(renderer.image(), swapchain, index);
        c.transition_swapchain(
            swapchain,
            index,
            Transition {
                old: L::TRANSFER_DST_OPTIMAL,
                new: L::COLOR_ATTACHMENT_OPTIMAL,
                src_stage: P::TRANSFER,
                src_access: A::TRANSFER_WRITE,
                dst_stage: P::COLOR_ATTACHMENT_OUTPUT,
                dst_access: A::COLOR_ATTACHMENT_READ | A::COLOR_ATTACHMENT_WRITE,
            },
        );
        if let Some(o) = &overlay {
            c.begin_overlay(swapchain, index);
            self.egui.cmd_draw(c.buffer(), extent, o.pixels_per_point, o.primitives).map_err(eerr)?;
            c.end_rendering();
        }
        let mut last = (L::COLOR_ATTACHMENT_OPTIMAL, P::COLOR_ATTACHMENT_OUTPUT, A::COLOR_ATTACHMENT_WRITE);
        if let Some((buf, _)) = &capture {
            c.transition_swapchain(swapchain, index, Transition::color_to_transfer_src());
            c.copy_swapchain_to_buffer(swapchain, index, buf);
            last = (L::TRANSFER_SRC_OPTIMAL, P::TRANSFER, A::empty());
        }
        c.transition_swapchain(
            swapchain,
            index,
            Transition {
                old: last.0,
                new: L::PRESENT_SRC_KHR,
                src_stage: last.1,
                src_access: last.2,
                dst_stage: P::BOTTOM_OF_PIPE,
                dst_access: A::empty(),
            },
        );
        let done = &self.done[index as usize];
        c.submit_with(&[(&slot.acquired, P::TRANSFER | P::COLOR_ATTACHMENT_OUTPUT)], &[done]).map_err(rerr)?;
        slot.pending = true;
        slot.capture = capture;
        if !swapchain.present(index, done).map_err(rerr)? {
            self.stale = true;
        }
        self.frame += 1;
        self.presented += 1;
        if let Some(o) = &overlay
            && !o.textures.free.is_empty()
        {
            self.settle()?;
            for id in &o.textures.free {
                self.egui.free_texture(*id).map_err(eerr)?;
            }
        }
        let m = self.dev.take_messages();
        if m.is_empty() { Ok(Presented::Frame) } else { Err(rerr(VkError::Validation(m.join(" | ")))) }
    }
}

fn is_srgb(format: vk::Format) -> bool {
    matches!(format, vk::Format::B8G8R8A8_SRGB | vk::Format::R8G8B8A8_SRGB | vk::Format::A8B8G8R8_SRGB_PACK32)
}

impl Drop for Presenter {
    fn drop(&mut self) {
        // Nothing may be in flight when the swapchain, semaphores and egui's buffers go.
        let _ = self.settle();
    }
}
