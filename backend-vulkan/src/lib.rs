//! clothlab-vulkan: the cloth solver on raw Vulkan through ash and gpu-allocator, running
//! the same SPIR-V kernels (from clothlab-shaders) and the same recipes as the wgpu backend,
//! so that the two differ only in the API and how it is driven.
//!
//! All `unsafe` is in the crate-private `raw` module, each block with a `// SAFETY:` line;
//! the engine, renderer and presenter above it are safe code over its RAII types.
//!
//! How it fits: `VulkanEngine` is this API's `clothlab_engine::Engine` (device-local
//! buffers through gpu-allocator, compute pipelines from clothlab-shaders' SPIR-V, push
//! constants, barriers derived from each kernel's reads and writes, timestamps); the
//! solver is `GpuSolver<VulkanEngine>`, the same generic solver the wgpu backend uses.
//! `VulkanRenderer` draws the same passes as the wgpu renderer (pixel-identical on
//! lavapipe) and `Presenter` puts them and egui on a window's swapchain for the app.
#![deny(unsafe_code)]

mod device;
pub mod overhead;
mod present;
pub(crate) mod raw;
mod render;
mod solver;

use thiserror::Error;

pub use clothlab_engine::recipe::StatsMode;
pub use clothlab_engine::{GpuSolver, SolverOptions, VariantSpec};
pub use device::Device;
pub use present::{Overlay, Presented, Presenter, Screenshot};
pub use render::{FRAMES_IN_FLIGHT, VkCloth, VulkanRenderer};
pub use solver::{VulkanEngine, VulkanSolver, vulkan_solver};

/// Why Vulkan could not be used.
#[derive(Debug, Error)]
pub enum VkError {
    /// No loader (libvulkan) on this system.
    #[error("no Vulkan loader found ({0}); on Linux, `apt-get install libvulkan1 mesa-vulkan-drivers`")]
    NoVulkan(String),
    /// A loader but no device with a compute queue.
    #[error(
        "no GPU adapter found (Vulkan); on Linux, `apt-get install mesa-vulkan-drivers` gives a software one (lavapipe)"
    )]
    NoAdapter,
    /// A Vulkan call failed.
    #[error("Vulkan error while {what}: {reason}")]
    Vulkan {
        /// What was being done.
        what: &'static str,
        /// The result code or allocator message.
        reason: String,
    },
    /// The validation layer reported problems.
    #[error("Vulkan validation: {0}")]
    Validation(String),
}
