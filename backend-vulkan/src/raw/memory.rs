//! Buffers and images with their memory (gpu-allocator).

use std::sync::Arc;

use ash::vk;
use gpu_allocator::MemoryLocation;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};

use super::device::Alive;
use super::{Device, range, vk_err};
use crate::VkError;

/// A buffer and its memory.
pub struct Buffer {
    pub(super) dev: Arc<Device>,
    /// The Vulkan buffer.
    pub buffer: vk::Buffer,
    pub(super) allocation: Option<Allocation>,
    /// Size, bytes.
    pub size: u64,
    pub(super) alive: Alive,
}

impl Buffer {
    /// A buffer of `size` bytes (at least 4) in `location`.
    pub fn new(
        dev: &Arc<Device>,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> Result<Self, VkError> {
        let size = size.max(4);
        let info = vk::BufferCreateInfo::default().size(size).usage(usage).sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: valid device and create info.
        let buffer = unsafe { dev.device.create_buffer(&info, None) }.map_err(vk_err("creating a buffer"))?;
        // SAFETY: `buffer` was just created on this device.
        let requirements = unsafe { dev.device.get_buffer_memory_requirements(buffer) };
        let allocation = dev
            .allocator
            .lock()
            .map_err(|_| VkError::Vulkan { what: "allocating", reason: "poisoned allocator".into() })?
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location,
                linear: true,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: the buffer is unused and unbound.
                unsafe { dev.device.destroy_buffer(buffer, None) };
                return Err(VkError::Vulkan { what: "allocating buffer memory", reason: e.to_string() });
            }
        };
        // SAFETY: the allocation satisfies the buffer's requirements and outlives it (it is
        // freed in Drop after the buffer is destroyed).
        unsafe { dev.device.bind_buffer_memory(buffer, allocation.memory(), allocation.offset()) }
            .map_err(vk_err("binding buffer memory"))?;
        Ok(Self { dev: dev.clone(), buffer, allocation: Some(allocation), size, alive: Alive::new() })
    }

    /// The mapped bytes of a host-visible buffer.
    pub fn mapped(&mut self) -> Option<&mut [u8]> {
        let size = self.size as usize;
        self.allocation.as_mut().and_then(|a| a.mapped_slice_mut()).map(|s| &mut s[..size])
    }

    /// The mapped bytes of a host-visible buffer, read only.
    pub fn bytes(&self) -> Option<&[u8]> {
        let size = self.size as usize;
        self.allocation.as_ref().and_then(|a| a.mapped_slice()).map(|s| &s[..size])
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        self.alive.end();
        let buffer = self.buffer;
        // SAFETY: retire runs this once the device is idle; a recording that used the
        // buffer and is not submitted yet is refused at submission.
        self.dev.retire(|d| unsafe { d.destroy_buffer(buffer, None) });
        if let (Some(a), Ok(mut alloc)) = (self.allocation.take(), self.dev.allocator.lock()) {
            let _ = alloc.free(a);
        }
    }
}

/// A device-local 2-D image and its view: the spring table read as texture memory, and
/// the renderer's targets, shadow map and fabric texture.
pub struct Image {
    pub(super) dev: Arc<Device>,
    pub(super) image: vk::Image,
    pub(super) view: vk::ImageView,
    pub(super) allocation: Option<Allocation>,
    /// Width, texels.
    pub width: u32,
    /// Height, texels.
    pub height: u32,
    /// Depth, texels (1 for a 2-D image).
    pub depth: u32,
    /// Texel format.
    pub format: vk::Format,
    /// Colour or depth.
    pub aspect: vk::ImageAspectFlags,
    pub(super) alive: Alive,
}

/// What an [`Image`] is.
#[derive(Debug, Clone, Copy)]
pub struct ImageDesc {
    /// Width, texels.
    pub width: u32,
    /// Height, texels.
    pub height: u32,
    /// Texel format.
    pub format: vk::Format,
    /// How it is used.
    pub usage: vk::ImageUsageFlags,
    /// Samples per texel.
    pub samples: vk::SampleCountFlags,
}

impl Image {
    /// The format of the spring-table image: four 32-bit words a texel.
    pub const FORMAT: vk::Format = vk::Format::R32G32B32A32_UINT;

    /// A `width × height` spring-table image, sampled by compute shaders and filled by
    /// transfer ([`Commands::copy_to_image`]).
    pub fn new(dev: &Arc<Device>, name: &str, width: u32, height: u32) -> Result<Self, VkError> {
        let usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
        Self::with_desc(
            dev,
            name,
            ImageDesc { width, height, format: Self::FORMAT, usage, samples: vk::SampleCountFlags::TYPE_1 },
        )
    }

    /// A `width × height × depth` 3-D image of `R32_SFLOAT` texels, sampled (with a
    /// filtering sampler) by compute shaders and filled by transfer
    /// ([`Commands::copy_to_image`]): the bodies' distance fields.
    pub fn volume(dev: &Arc<Device>, name: &str, width: u32, height: u32, depth: u32) -> Result<Self, VkError> {
        let most = dev.max_image_3d;
        if width == 0 || height == 0 || depth == 0 || width.max(height).max(depth) > most {
            return Err(VkError::Vulkan {
                what: "creating a 3-D image",
                reason: format!("{width} × {height} × {depth} texels; this device allows 1 … {most} a side"),
            });
        }
        let usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
        let desc =
            ImageDesc { width, height, format: vk::Format::R32_SFLOAT, usage, samples: vk::SampleCountFlags::TYPE_1 };
        Self::make(dev, name, desc, Some(depth))
    }

    /// An image as `desc` says.
    pub fn with_desc(dev: &Arc<Device>, name: &str, desc: ImageDesc) -> Result<Self, VkError> {
        if desc.width > dev.max_image_2d || desc.height > dev.max_image_2d {
            return Err(VkError::Vulkan {
                what: "creating an image",
                reason: format!(
                    "{} × {} texels; this device allows 1 … {} a side",
                    desc.width, desc.height, dev.max_image_2d
                ),
            });
        }
        Self::make(dev, name, desc, None)
    }

    /// A 2-D image, or a 3-D one of `volume` slices (even one: the view's type must be
    /// the shader's), sides checked by the caller.
    fn make(dev: &Arc<Device>, name: &str, desc: ImageDesc, volume: Option<u32>) -> Result<Self, VkError> {
        let ImageDesc { width, height, format, usage, samples } = desc;
        let depth = volume.unwrap_or(1);
        let aspect =
            if format == vk::Format::D32_SFLOAT { vk::ImageAspectFlags::DEPTH } else { vk::ImageAspectFlags::COLOR };
        if width == 0 || height == 0 || depth == 0 {
            return Err(VkError::Vulkan {
                what: "creating an image",
                reason: format!("{width} × {height} × {depth} texels: a side of 0"),
            });
        }
        let kind = if volume.is_some() { vk::ImageType::TYPE_3D } else { vk::ImageType::TYPE_2D };
        let info = vk::ImageCreateInfo::default()
            .image_type(kind)
            .format(format)
            .extent(vk::Extent3D { width, height, depth })
            .mip_levels(1)
            .array_layers(1)
            .samples(samples)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        let d = &dev.device;
        // SAFETY: valid device and create info.
        let image = unsafe { d.create_image(&info, None) }.map_err(vk_err("creating an image"))?;
        // SAFETY: `image` was just created on this device.
        let requirements = unsafe { d.get_image_memory_requirements(image) };
        let allocation = dev
            .allocator
            .lock()
            .map_err(|_| VkError::Vulkan { what: "allocating", reason: "poisoned allocator".into() })
            .and_then(|mut a| {
                a.allocate(&AllocationCreateDesc {
                    name,
                    requirements,
                    location: MemoryLocation::GpuOnly,
                    linear: false,
                    allocation_scheme: AllocationScheme::GpuAllocatorManaged,
                })
                .map_err(|e| VkError::Vulkan { what: "allocating image memory", reason: e.to_string() })
            });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: the image is unused and unbound.
                unsafe { d.destroy_image(image, None) };
                return Err(e);
            }
        };
        let mut me = Self {
            dev: dev.clone(),
            image,
            view: vk::ImageView::null(),
            allocation: None,
            width,
            height,
            depth,
            format,
            aspect,
            alive: Alive::new(),
        };
        // SAFETY: the allocation satisfies the image's requirements and is freed in Drop
        // after the image is destroyed.
        unsafe { d.bind_image_memory(image, allocation.memory(), allocation.offset()) }
            .map_err(vk_err("binding image memory"))?;
        me.allocation = Some(allocation);
        let view_info = vk::ImageViewCreateInfo::default()
            .image(image)
            .view_type(if volume.is_some() { vk::ImageViewType::TYPE_3D } else { vk::ImageViewType::TYPE_2D })
            .format(format)
            .subresource_range(range(aspect));
        // SAFETY: the image is live and bound; the view is destroyed first in Drop.
        me.view = unsafe { d.create_image_view(&view_info, None) }.map_err(vk_err("creating an image view"))?;
        Ok(me)
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        self.alive.end();
        let (view, image) = (self.view, self.image);
        // SAFETY: retire runs this once the device is idle (see Buffer); view, image,
        // memory in reverse order (a null view is ignored by vkDestroyImageView).
        self.dev.retire(|d| unsafe {
            d.destroy_image_view(view, None);
            d.destroy_image(image, None);
        });
        if let (Some(a), Ok(mut alloc)) = (self.allocation.take(), self.dev.allocator.lock()) {
            let _ = alloc.free(a);
        }
    }
}
