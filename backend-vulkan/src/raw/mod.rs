//! The only unsafe code of clothlab: thin RAII wrappers over the Vulkan objects the
//! backend uses, split by concern — [`device`] (instance, device, queue, allocator, the
//! validation layer), [`memory`] (buffers, images), [`pipelines`] (compute pipelines,
//! descriptor sets), [`commands`] (recording and submitting compute and transfer work),
//! `graphics` (the renderer's pipelines and drawing) and `surface` (swapchain,
//! presenting). Every object holds an `Arc<Device>`, so it is destroyed before the device.
//!
//! Soundness of the safe surface (no safe function relies on its caller):
//! * an object is destroyed only after the device is idle ([`Device::retire`]), so no
//!   submitted work can still use it;
//! * a command buffer that recorded an object dropped before the submission is refused
//!   at submission (the device counts destructions; a recording remembers the count);
//! * a descriptor set ([`Set`]) keeps the buffers and images it points at, and its pool,
//!   alive;
//! * copies check their ranges against the buffers and images they name.
#![allow(unsafe_code)]

mod commands;
mod device;
mod graphics;
mod memory;
mod pipelines;
mod surface;

pub use commands::{Commands, Dispatch};
pub use device::Device;
pub use graphics::{Binding, GraphicsPipeline, PipelineDesc, PipelineLayout, Sampler, Transition, VertexBinding};
pub use memory::{Buffer, Image, ImageDesc};
pub use pipelines::{Kernel, Set, Sets};
pub use surface::{Acquired, Semaphore, Swapchain};

use ash::vk;

use crate::VkError;

fn vk_err(what: &'static str) -> impl Fn(vk::Result) -> VkError {
    move |e| VkError::Vulkan { what, reason: format!("{e:?}") }
}

fn range(aspect: vk::ImageAspectFlags) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange::default().aspect_mask(aspect).level_count(1).layer_count(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_validation_layer_reports_into_the_message_list() {
        let dev = match Device::new(true) {
            Ok(d) => d,
            Err(e) if std::env::var("CLOTHLAB_REQUIRE_GPU").as_deref() != Ok("1") => {
                eprintln!("skipped: {e}");
                return;
            }
            Err(e) => panic!("{e}"),
        };
        if !dev.validation {
            assert_ne!(
                std::env::var("CLOTHLAB_REQUIRE_GPU").as_deref(),
                Ok("1"),
                "CI installs vulkan-validationlayers"
            );
            eprintln!("skipped: validation layer not installed");
            return;
        }
        assert!(dev.take_messages().is_empty(), "a clean device reports nothing");
        // A zero-sized buffer breaks a valid-usage rule (VkBufferCreateInfo::size > 0) that
        // drivers tolerate: the layer must report it.
        let info = vk::BufferCreateInfo::default().size(0).usage(vk::BufferUsageFlags::STORAGE_BUFFER);
        // SAFETY: deliberately invalid usage of a harmless call, to see the layer report it;
        // the buffer, if any, is destroyed at once and never bound or used.
        unsafe {
            if let Ok(b) = dev.device.create_buffer(&info, None) {
                dev.device.destroy_buffer(b, None);
            }
        }
        let m = dev.take_messages();
        assert!(!m.is_empty(), "the validation layer said nothing about a zero-sized buffer");
        println!("validation layer: {}", m[0]);
    }
}
