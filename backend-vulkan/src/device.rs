//! The public device handle: what the app and the tests may do with a Vulkan device
//! (open it, name it, wait for it, check it for leaks and validation messages). The raw
//! device behind it, with its loaders, queue and allocator, stays private to the crate.

use std::sync::Arc;

use crate::{VkError, raw};

/// A Vulkan device (instance, physical device, one queue, the allocator), shared by
/// solvers, renderers and presenters; cloning shares it. It is released once the last
/// clone and everything made on it are gone.
#[derive(Clone)]
pub struct Device(Arc<raw::Device>);

impl std::fmt::Debug for Device {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_tuple("Device").field(&self.0.name).finish()
    }
}

impl Device {
    /// Loads Vulkan and opens the first device with a compute queue, with the Khronos
    /// validation layer when `validation` is set and the layer is installed.
    pub fn new(validation: bool) -> Result<Self, VkError> {
        raw::Device::new(validation).map(Self)
    }

    /// Like [`Device::new`], for drawing into `window` too (see [`crate::Presenter`]).
    pub fn for_window(
        validation: bool,
        window: &(impl raw_window_handle::HasDisplayHandle + raw_window_handle::HasWindowHandle),
    ) -> Result<Self, VkError> {
        raw::Device::for_window(validation, window).map(Self)
    }

    /// The adapter's name as the driver reports it.
    pub fn name(&self) -> &str {
        &self.0.name
    }

    /// Waits until the device has nothing left to do.
    pub fn wait_idle(&self) -> Result<(), VkError> {
        self.0.wait_idle()
    }

    /// Allocations the allocator holds now (0 once everything made on the device is
    /// dropped: the leak check).
    pub fn live_allocations(&self) -> usize {
        self.0.live_allocations()
    }

    /// Takes the validation-layer messages gathered so far (none when it is off).
    pub fn take_messages(&self) -> Vec<String> {
        self.0.take_messages()
    }

    /// The raw device, for the crate's own objects.
    pub(crate) fn raw(&self) -> &Arc<raw::Device> {
        &self.0
    }

    /// Wraps a raw device the crate already holds.
    pub(crate) fn from_raw(dev: &Arc<raw::Device>) -> Self {
        Self(dev.clone())
    }
}
