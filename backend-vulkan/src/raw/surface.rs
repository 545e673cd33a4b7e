//! The window half of the raw layer: semaphores, the swapchain on the device's surface,
//! and the commands that put a rendered image on screen.

use std::sync::Arc;

use super::*;

/// A binary semaphore.
pub struct Semaphore {
    dev: Arc<Device>,
    /// The Vulkan semaphore.
    pub semaphore: vk::Semaphore,
}

impl Semaphore {
    /// A new, unsignalled semaphore.
    pub fn new(dev: &Arc<Device>) -> Result<Self, VkError> {
        // SAFETY: valid device and create info; destroyed in Drop.
        let semaphore = unsafe { dev.device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }
            .map_err(vk_err("creating a semaphore"))?;
        Ok(Self { dev: dev.clone(), semaphore })
    }
}

impl Drop for Semaphore {
    fn drop(&mut self) {
        let semaphore = self.semaphore;
        // SAFETY: retire runs this once the device is idle.
        self.dev.retire(|d| unsafe { d.destroy_semaphore(semaphore, None) });
    }
}

/// What acquiring a swapchain image gave.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Acquired {
    /// Image `index`; `suboptimal` asks for a new swapchain after presenting.
    Image {
        /// Index into the swapchain's images.
        index: u32,
        /// The surface changed; the image still presents.
        suboptimal: bool,
    },
    /// The swapchain no longer matches the surface: make a new one.
    OutOfDate,
}

/// A swapchain with a view per image.
pub struct Swapchain {
    dev: Arc<Device>,
    swapchain: vk::SwapchainKHR,
    /// The images (owned by the swapchain).
    pub images: Vec<vk::Image>,
    views: Vec<vk::ImageView>,
    /// Image format (an sRGB one where the surface offers it).
    pub format: vk::Format,
    /// Image size.
    pub extent: vk::Extent2D,
    /// The images can be copied out (screenshots).
    pub capturable: bool,
}

impl Swapchain {
    /// A swapchain of about `width × height` (clamped to what the surface allows) on the
    /// device's surface, replacing `old` when given. `None` when the surface has zero
    /// extent (a minimised window): nothing can be presented until it changes.
    pub fn new(dev: &Arc<Device>, width: u32, height: u32, old: Option<&Swapchain>) -> Result<Option<Self>, VkError> {
        let (Some(loader), Some(sl)) = (&dev.swapchain_loader, &dev.surface_loader) else {
            return Err(VkError::Vulkan { what: "creating a swapchain", reason: "the device has no window".into() });
        };
        // SAFETY: physical device and surface belong to this device's instance.
        let (caps, formats, modes) = unsafe {
            (
                sl.get_physical_device_surface_capabilities(dev.physical, dev.surface)
                    .map_err(vk_err("reading the surface capabilities"))?,
                sl.get_physical_device_surface_formats(dev.physical, dev.surface)
                    .map_err(vk_err("reading the surface formats"))?,
                sl.get_physical_device_surface_present_modes(dev.physical, dev.surface)
                    .map_err(vk_err("reading the present modes"))?,
            )
        };
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: width.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: height.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        if extent.width == 0 || extent.height == 0 {
            return Ok(None);
        }
        let srgb = [vk::Format::B8G8R8A8_SRGB, vk::Format::R8G8B8A8_SRGB];
        let format = formats
            .iter()
            .find(|f| srgb.contains(&f.format) && f.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR)
            .or(formats.first())
            .copied()
            .ok_or(VkError::Vulkan { what: "choosing a surface format", reason: "the surface offers none".into() })?;
        // FIFO always exists; MAILBOX (no tearing, no blocking) where offered.
        let mode = if modes.contains(&vk::PresentModeKHR::MAILBOX) {
            vk::PresentModeKHR::MAILBOX
        } else {
            vk::PresentModeKHR::FIFO
        };
        // TRANSFER_SRC where offered: screenshots of what the window shows.
        let mut usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_DST;
        let capturable = caps.supported_usage_flags.contains(vk::ImageUsageFlags::TRANSFER_SRC);
        if capturable {
            usage |= vk::ImageUsageFlags::TRANSFER_SRC;
        }
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(dev.surface)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
            .present_mode(mode)
            .clipped(true)
            .old_swapchain(old.map_or(vk::SwapchainKHR::null(), |o| o.swapchain));
        // SAFETY: valid device with the swapchain extension; `old` (if any) is retired by
        // this call and destroyed by its owner after the device is idle.
        let swapchain = unsafe { loader.create_swapchain(&info, None) }.map_err(vk_err("creating a swapchain"))?;
        let mut me = Self {
            dev: dev.clone(),
            swapchain,
            images: Vec::new(),
            views: Vec::new(),
            format: format.format,
            extent,
            capturable,
        };
        // SAFETY: the swapchain was just created.
        me.images = unsafe { loader.get_swapchain_images(swapchain) }.map_err(vk_err("listing swapchain images"))?;
        for &image in &me.images {
            let view_info = vk::ImageViewCreateInfo::default()
                .image(image)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(me.format)
                .subresource_range(range(vk::ImageAspectFlags::COLOR));
            // SAFETY: the image belongs to the swapchain; the view is destroyed in Drop.
            let view = unsafe { dev.device.create_image_view(&view_info, None) }
                .map_err(vk_err("creating a swapchain view"))?;
            me.views.push(view);
        }
        Ok(Some(me))
    }

    /// The view of image `index`.
    pub fn view(&self, index: u32) -> vk::ImageView {
        self.views[index as usize]
    }

    /// Acquires the next image, signalling `signal` when it may be drawn into.
    pub fn acquire(&self, signal: &Semaphore) -> Result<Acquired, VkError> {
        let loader = self.dev.swapchain_loader.as_ref().expect("a swapchain implies the loader");
        // SAFETY: the semaphore is unsignalled with no pending signal (its frame slot was
        // waited for); no fence.
        match unsafe { loader.acquire_next_image(self.swapchain, u64::MAX, signal.semaphore, vk::Fence::null()) } {
            Ok((index, suboptimal)) => Ok(Acquired::Image { index, suboptimal }),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Acquired::OutOfDate),
            Err(e) => Err(vk_err("acquiring a swapchain image")(e)),
        }
    }

    /// Presents image `index` once `wait` is signalled; `false` when the swapchain is
    /// out of date or suboptimal and should be made anew.
    pub fn present(&self, index: u32, wait: &Semaphore) -> Result<bool, VkError> {
        let loader = self.dev.swapchain_loader.as_ref().expect("a swapchain implies the loader");
        let swapchains = [self.swapchain];
        let indices = [index];
        let waits = [wait.semaphore];
        let info =
            vk::PresentInfoKHR::default().wait_semaphores(&waits).swapchains(&swapchains).image_indices(&indices);
        if index as usize >= self.images.len() {
            return Err(VkError::Vulkan { what: "presenting", reason: format!("no swapchain image {index}") });
        }
        let _queue = self.dev.queue();
        // SAFETY: the queue lock is held; the image exists (checked), was acquired, and the
        // submission rendering it signals `wait`.
        match unsafe { loader.queue_present(self.dev.queue, &info) } {
            Ok(false) => Ok(true),
            Ok(true) | Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(false),
            Err(e) => Err(vk_err("presenting")(e)),
        }
    }
}

impl Drop for Swapchain {
    fn drop(&mut self) {
        let (views, swapchain) = (std::mem::take(&mut self.views), self.swapchain);
        let loader = self.dev.swapchain_loader.clone();
        // SAFETY: retire runs this once the device is idle.
        self.dev.retire(|d| unsafe {
            for v in &views {
                d.destroy_image_view(*v, None);
            }
            if let Some(loader) = &loader {
                loader.destroy_swapchain(swapchain, None);
            }
        });
    }
}

impl Commands {
    /// Ends the active buffer and submits it, waiting for `wait` (at the given stages),
    /// signalling `signal`, and the fence (see [`Commands::wait`]).
    pub fn submit_with(
        &self,
        wait: &[(&Semaphore, vk::PipelineStageFlags)],
        signal: &[&Semaphore],
    ) -> Result<(), VkError> {
        let wait_sems: Vec<vk::Semaphore> = wait.iter().map(|(s, _)| s.semaphore).collect();
        let stages: Vec<vk::PipelineStageFlags> = wait.iter().map(|(_, st)| *st).collect();
        let signal_sems: Vec<vk::Semaphore> = signal.iter().map(|s| s.semaphore).collect();
        self.submit_info(true, &wait_sems, &stages, &signal_sems)
    }

    /// A layout transition of image `index` of `swapchain` (colour).
    pub fn transition_swapchain(&self, swapchain: &Swapchain, index: u32, t: Transition) {
        let Some(&image) = swapchain.images.get(index as usize) else {
            self.poison("no such swapchain image");
            return;
        };
        self.transition_handle(image, vk::ImageAspectFlags::COLOR, t);
    }

    /// Copies all of `src` (TRANSFER_SRC_OPTIMAL) onto swapchain image `dst`
    /// (TRANSFER_DST_OPTIMAL) of the same size, converting the format.
    pub fn blit_to_swapchain(&self, src: &Image, swapchain: &Swapchain, index: u32) {
        let (Some(&dst), extent) = (swapchain.images.get(index as usize), swapchain.extent) else {
            self.poison("no such swapchain image");
            return;
        };
        if !self.recording() {
            return;
        }
        let corner = |w: u32, h: u32| [vk::Offset3D::default(), vk::Offset3D { x: w as i32, y: h as i32, z: 1 }];
        let layers = vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1);
        let region = [vk::ImageBlit::default()
            .src_subresource(layers)
            .src_offsets(corner(src.width, src.height))
            .dst_subresource(layers)
            .dst_offsets(corner(extent.width, extent.height))];
        // SAFETY: recording state; both images are live and in the named layouts.
        unsafe {
            self.dev.device.cmd_blit_image(
                self.cmd(),
                src.image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                dst,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &region,
                vk::Filter::NEAREST,
            )
        };
    }

    /// Begins dynamic rendering onto `view` (COLOR_ATTACHMENT_OPTIMAL) keeping what is
    /// there: the egui pass over the scene.
    pub fn begin_overlay(&self, swapchain: &Swapchain, index: u32) {
        let (Some(&view), extent) = (swapchain.views.get(index as usize), swapchain.extent) else {
            self.poison("no such swapchain image");
            return;
        };
        if !self.recording() {
            return;
        }
        let color = [vk::RenderingAttachmentInfo::default()
            .image_view(view)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::LOAD)
            .store_op(vk::AttachmentStoreOp::STORE)];
        let info = vk::RenderingInfo::default()
            .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent })
            .layer_count(1)
            .color_attachments(&color);
        // SAFETY: recording state, outside rendering; dynamic rendering is enabled.
        unsafe { self.dev.device.cmd_begin_rendering(self.cmd(), &info) };
    }

    /// Copies swapchain image `image` (TRANSFER_SRC_OPTIMAL) into `dst`, tightly packed.
    pub fn copy_swapchain_to_buffer(&self, swapchain: &Swapchain, index: u32, dst: &Buffer) {
        let (Some(&image), extent) = (swapchain.images.get(index as usize), swapchain.extent) else {
            self.poison("no such swapchain image");
            return;
        };
        if !self.recording() || !swapchain.capturable || dst.size < extent.width as u64 * extent.height as u64 * 4 {
            self.poison("a screenshot into a buffer too small, or of a swapchain that cannot be copied");
            return;
        }
        let region = [vk::BufferImageCopy::default()
            .image_subresource(
                vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1),
            )
            .image_extent(vk::Extent3D { width: extent.width, height: extent.height, depth: 1 })];
        // SAFETY: recording state; `dst` holds width × height × 4 bytes (the presenter
        // sizes it) and the image belongs to a live swapchain created with TRANSFER_SRC.
        unsafe {
            self.dev.device.cmd_copy_image_to_buffer(
                self.cmd(),
                image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                dst.buffer,
                &region,
            )
        };
    }

    /// The command pool (egui-ash-renderer uploads its textures through it).
    pub fn pool(&self) -> vk::CommandPool {
        self.pool
    }

    /// The buffer being recorded.
    pub fn buffer(&self) -> vk::CommandBuffer {
        self.cmd()
    }
}
