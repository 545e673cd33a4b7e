//! The only unsafe code of clothlab: thin RAII wrappers over the Vulkan objects the
//! solver uses. Every object holds an `Arc<Device>`, so it is destroyed before the device;
//! the device waits for idle, drops the allocator, then destroys itself, the debug
//! messenger and the instance, in reverse creation order.
#![allow(unsafe_code)]

mod graphics;
mod surface;

pub use graphics::{Binding, GraphicsPipeline, PipelineDesc, PipelineLayout, Sampler, Transition, VertexBinding};
pub use surface::{Acquired, Semaphore, Swapchain};

use std::ffi::{CStr, c_void};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex};

use ash::vk;
use gpu_allocator::MemoryLocation;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme, Allocator, AllocatorCreateDesc};

use crate::VkError;

const VALIDATION: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Messages of the validation layer (warnings and errors), in order.
pub type Messages = Arc<Mutex<Vec<String>>>;

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the layer passes valid callback data for the duration of the call, and
    // `user` is the `Mutex<Vec<String>>` inside the `Messages` Arc that `Device` keeps
    // alive until after the messenger is destroyed.
    unsafe {
        if data.is_null() || user.is_null() {
            return vk::FALSE;
        }
        let msg = (*data).message_as_c_str().map(|m| m.to_string_lossy().into_owned()).unwrap_or_default();
        let sink = &*(user as *const Mutex<Vec<String>>);
        if severity
            .intersects(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING)
            && let Ok(mut v) = sink.lock()
        {
            v.push(msg);
        }
    }
    vk::FALSE
}

/// Instance, physical device, logical device, queue and allocator.
pub struct Device {
    _entry: ash::Entry,
    instance: ash::Instance,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// Validation-layer messages (empty when the layer is off).
    pub messages: Messages,
    /// Whether the validation layer is on.
    pub validation: bool,
    /// The physical device.
    pub physical: vk::PhysicalDevice,
    /// The logical device.
    pub device: ash::Device,
    /// A queue with compute.
    pub queue: vk::Queue,
    /// Its family.
    pub queue_family: u32,
    allocator: ManuallyDrop<Mutex<Allocator>>,
    /// Adapter name.
    pub name: String,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period: f32,
    /// Whether the queue writes timestamps.
    pub timestamps: bool,
    /// Largest push-constant block, bytes.
    pub max_push_constants: u32,
    /// `atomicAdd` on `f32` in storage buffers (VK_EXT_shader_atomic_float), enabled.
    pub float_atomics: bool,
    /// Largest storage-buffer binding, bytes.
    pub max_storage_range: u64,
    /// Invocations per subgroup (0 when unknown).
    pub subgroup_size: u32,
    /// Subgroup arithmetic (subgroupAdd, subgroupMax) in compute shaders.
    pub subgroup_arithmetic: bool,
    /// synchronization2 (Vulkan 1.3) enabled: timestamps by `vkCmdWriteTimestamp2`,
    /// barriers by `vkCmdPipelineBarrier2`.
    pub sync2: bool,
    /// Largest 2-D image side, texels.
    pub max_image_2d: u32,
    /// The queue draws too, with dynamic rendering (Vulkan 1.3): the renderer can run.
    pub dynamic_rendering: bool,
    /// The window's surface (null without a window).
    pub surface: vk::SurfaceKHR,
    /// Surface queries (with a window).
    pub surface_loader: Option<ash::khr::surface::Instance>,
    /// Swapchain functions (with a window).
    pub swapchain_loader: Option<ash::khr::swapchain::Device>,
}

impl Device {
    /// Loads Vulkan, opens the first device with a compute queue, with the Khronos
    /// validation layer when `validation` is set and the layer is installed.
    pub fn new(validation: bool) -> Result<Arc<Self>, VkError> {
        Ok(Self::open(validation, None)?.0)
    }

    /// Like [`Device::new`], for drawing into `window` too: the instance gets the surface
    /// extensions, the queue must present to the window's surface, and the device gets
    /// VK_KHR_swapchain. The surface is owned by the device.
    pub fn for_window(
        validation: bool,
        window: &(impl raw_window_handle::HasDisplayHandle + raw_window_handle::HasWindowHandle),
    ) -> Result<Arc<Self>, VkError> {
        let handles = window
            .display_handle()
            .and_then(|d| window.window_handle().map(|w| (d.as_raw(), w.as_raw())))
            .map_err(|e| VkError::Vulkan { what: "reading the window handles", reason: e.to_string() })?;
        Ok(Self::open(validation, Some(handles))?.0)
    }

    fn open(
        validation: bool,
        window: Option<(raw_window_handle::RawDisplayHandle, raw_window_handle::RawWindowHandle)>,
    ) -> Result<(Arc<Self>, ()), VkError> {
        // SAFETY: loading the system's Vulkan loader; its functions are used through ash's
        // tables only while `_entry` lives (it is a field of the returned Device).
        let entry = unsafe { ash::Entry::load() }.map_err(|e| VkError::NoVulkan(e.to_string()))?;
        // SAFETY: plain enumeration call with a valid entry.
        let layers = unsafe { entry.enumerate_instance_layer_properties() }.map_err(vk_err("listing layers"))?;
        let has_layer = layers.iter().any(|l| l.layer_name_as_c_str().is_ok_and(|n| n == VALIDATION));
        let validation = validation && has_layer;
        if !has_layer {
            log::info!("Vulkan validation layer not installed (package vulkan-validationlayers)");
        }
        let app = vk::ApplicationInfo::default().application_name(c"clothlab").api_version(vk::API_VERSION_1_3);
        let layer_names = [VALIDATION.as_ptr()];
        // The layer's synchronization validation checks that the barriers the solver
        // leaves out are really not needed (hazards are reported as errors).
        // SAFETY: plain enumeration call with a valid entry and layer name.
        let layer_exts = unsafe { entry.enumerate_instance_extension_properties(Some(VALIDATION)) }.unwrap_or_default();
        let has_features = layer_exts
            .iter()
            .any(|e| e.extension_name_as_c_str().is_ok_and(|n| n == ash::ext::validation_features::NAME));
        let mut ext_names = Vec::new();
        if let Some((display, _)) = window {
            let surface_exts =
                ash_window::enumerate_required_extensions(display).map_err(vk_err("listing the surface extensions"))?;
            ext_names.extend_from_slice(surface_exts);
        }
        if validation {
            ext_names.push(ash::ext::debug_utils::NAME.as_ptr());
            if has_features {
                ext_names.push(ash::ext::validation_features::NAME.as_ptr());
            }
        }
        let enables = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);
        let mut info = vk::InstanceCreateInfo::default().application_info(&app).enabled_extension_names(&ext_names);
        if validation {
            info = info.enabled_layer_names(&layer_names);
            if has_features {
                info = info.push_next(&mut features);
            }
        }
        // SAFETY: `info` and everything it points to live until the call returns.
        let instance = unsafe { entry.create_instance(&info, None) }.map_err(|e| match e {
            // The loader found no driver at all.
            vk::Result::ERROR_INCOMPATIBLE_DRIVER => VkError::NoAdapter,
            e => vk_err("creating the instance")(e),
        })?;
        let messages: Messages = Arc::new(Mutex::new(Vec::new()));
        let debug = if validation {
            let loader = ash::ext::debug_utils::Instance::new(&entry, &instance);
            let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                        | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
                )
                .pfn_user_callback(Some(debug_callback))
                .user_data(Arc::as_ptr(&messages) as *mut c_void);
            // SAFETY: the user data points into `messages`, which the Device owns and drops
            // only after destroying this messenger.
            let m = unsafe { loader.create_debug_utils_messenger(&info, None) }
                .map_err(vk_err("creating the messenger"))?;
            Some((loader, m))
        } else {
            None
        };
        // Surface functions exist only with the surface extensions (a window).
        let surface_loader = window.map(|_| ash::khr::surface::Instance::new(&entry, &instance));
        let surface = match window {
            // SAFETY: the handles come from a live window that the caller keeps open
            // while the device lives (the app drops the device before the window).
            Some((display, win)) => unsafe { ash_window::create_surface(&entry, &instance, display, win, None) }
                .map_err(vk_err("creating the window surface")),
            None => Ok(vk::SurfaceKHR::null()),
        };
        let fail = |e: VkError,
                    debug: &Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
                    surface: vk::SurfaceKHR| {
            // SAFETY: nothing else was created from the instance yet (a null surface is
            // ignored).
            unsafe {
                if let Some(sl) = &surface_loader {
                    sl.destroy_surface(surface, None);
                }
                if let Some((l, m)) = debug {
                    l.destroy_debug_utils_messenger(*m, None);
                }
                instance.destroy_instance(None);
            }
            e
        };
        let surface = match surface {
            Ok(s) => s,
            Err(e) => return Err(fail(e, &debug, vk::SurfaceKHR::null())),
        };
        // SAFETY: valid instance.
        let physicals = unsafe { instance.enumerate_physical_devices() }.map_err(vk_err("listing devices"));
        let physicals = match physicals {
            Ok(p) => p,
            Err(e) => return Err(fail(e, &debug, surface)),
        };
        let mut choice = None;
        for &pd in &physicals {
            // SAFETY: `pd` comes from this instance.
            let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
            // A family with graphics and compute (the renderer draws from the solver's
            // buffers on the same queue), else one with compute.
            let both = vk::QueueFlags::COMPUTE | vk::QueueFlags::GRAPHICS;
            // With a window, the family must also present to its surface.
            let presents = |k: usize| {
                match &surface_loader {
                    None => true,
                    // SAFETY: `pd`, `k` and `surface` belong to this instance.
                    Some(sl) => {
                        unsafe { sl.get_physical_device_surface_support(pd, k as u32, surface) }.unwrap_or(false)
                    }
                }
            };
            let family =
                families.iter().enumerate().position(|(k, f)| f.queue_flags.contains(both) && presents(k)).or_else(
                    || {
                        if surface != vk::SurfaceKHR::null() {
                            return None;
                        }
                        families.iter().position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
                    },
                );
            if let Some(f) = family {
                // SAFETY: as above.
                let props = unsafe { instance.get_physical_device_properties(pd) };
                let discrete = props.device_type == vk::PhysicalDeviceType::DISCRETE_GPU;
                if choice.is_none() || discrete {
                    choice = Some((pd, f as u32, props, families[f].timestamp_valid_bits > 0));
                }
            }
        }
        let Some((physical, queue_family, props, timestamps)) = choice else {
            return Err(fail(VkError::NoAdapter, &debug, surface));
        };
        // SAFETY: `physical` belongs to `instance`.
        let graphics = unsafe { instance.get_physical_device_queue_family_properties(physical) }[queue_family as usize]
            .queue_flags
            .contains(vk::QueueFlags::GRAPHICS);
        // Float atomic add on storage buffers, where the device has it: the naive recipe's
        // scatters then use the same kernels as on wgpu.
        // SAFETY: `physical` belongs to `instance`.
        let extensions = unsafe { instance.enumerate_device_extension_properties(physical) }.unwrap_or_default();
        let has_ext = extensions
            .iter()
            .any(|e| e.extension_name_as_c_str().is_ok_and(|n| n == ash::ext::shader_atomic_float::NAME));
        let mut atomic_query = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default();
        if has_ext {
            let mut features2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut atomic_query);
            // SAFETY: the query chain lives across the call; Vulkan 1.1+ core entry point.
            unsafe { instance.get_physical_device_features2(physical, &mut features2) };
        }
        let float_atomics = has_ext && atomic_query.shader_buffer_float32_atomic_add == vk::TRUE;
        // Subgroup size and operations (Vulkan 1.1 core).
        let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
        {
            let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut subgroup);
            // SAFETY: the query chain lives across the call.
            unsafe { instance.get_physical_device_properties2(physical, &mut props2) };
        }
        let subgroup_arithmetic = subgroup.supported_stages.contains(vk::ShaderStageFlags::COMPUTE)
            && subgroup
                .supported_operations
                .contains(vk::SubgroupFeatureFlags::BASIC | vk::SubgroupFeatureFlags::ARITHMETIC);
        // synchronization2, where the device is Vulkan 1.3.
        let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
        if props.api_version >= vk::API_VERSION_1_3 {
            let mut features2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f13);
            // SAFETY: the query chain lives across the call.
            unsafe { instance.get_physical_device_features2(physical, &mut features2) };
        }
        let sync2 = f13.synchronization2 == vk::TRUE;
        let dynamic_rendering = f13.dynamic_rendering == vk::TRUE && graphics;
        let mut enable13 =
            vk::PhysicalDeviceVulkan13Features::default().synchronization2(sync2).dynamic_rendering(dynamic_rendering);
        let mut atomic_enable = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default()
            .shader_buffer_float32_atomics(true)
            .shader_buffer_float32_atomic_add(true);
        let mut device_exts = Vec::new();
        if float_atomics {
            device_exts.push(ash::ext::shader_atomic_float::NAME.as_ptr());
        }
        if surface != vk::SurfaceKHR::null() {
            device_exts.push(ash::khr::swapchain::NAME.as_ptr());
        }
        let priorities = [1.0f32];
        let queue_info =
            [vk::DeviceQueueCreateInfo::default().queue_family_index(queue_family).queue_priorities(&priorities)];
        let mut dinfo =
            vk::DeviceCreateInfo::default().queue_create_infos(&queue_info).enabled_extension_names(&device_exts);
        if float_atomics {
            dinfo = dinfo.push_next(&mut atomic_enable);
        }
        if sync2 || dynamic_rendering {
            dinfo = dinfo.push_next(&mut enable13);
        }
        // SAFETY: `physical` belongs to `instance`; the create info outlives the call.
        let device = match unsafe { instance.create_device(physical, &dinfo, None) } {
            Ok(d) => d,
            Err(e) => return Err(fail(vk_err("creating the device")(e), &debug, surface)),
        };
        // SAFETY: the family was requested with one queue.
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device: physical,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        });
        let allocator = match allocator {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: the device has no objects yet.
                unsafe { device.destroy_device(None) };
                let e = VkError::Vulkan { what: "creating the allocator", reason: e.to_string() };
                return Err(fail(e, &debug, surface));
            }
        };
        let name = props.device_name_as_c_str().map(|c| c.to_string_lossy().into_owned()).unwrap_or_default();
        let swapchain_loader =
            (surface != vk::SurfaceKHR::null()).then(|| ash::khr::swapchain::Device::new(&instance, &device));
        let dev = Arc::new(Self {
            _entry: entry,
            instance,
            debug,
            messages,
            validation,
            physical,
            device,
            queue,
            queue_family,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            name,
            timestamp_period: props.limits.timestamp_period,
            timestamps: timestamps && props.limits.timestamp_compute_and_graphics == vk::TRUE,
            max_push_constants: props.limits.max_push_constants_size,
            float_atomics,
            max_storage_range: props.limits.max_storage_buffer_range as u64,
            subgroup_size: subgroup.subgroup_size,
            subgroup_arithmetic,
            sync2,
            max_image_2d: props.limits.max_image_dimension2_d,
            dynamic_rendering,
            surface,
            surface_loader,
            swapchain_loader,
        });
        Ok((dev, ()))
    }

    /// Allocations gpu-allocator holds now (0 once every buffer and image is dropped:
    /// the leak check).
    pub fn live_allocations(&self) -> usize {
        self.allocator.lock().map(|a| a.generate_report().allocations.len()).unwrap_or(usize::MAX)
    }

    /// The instance (for libraries that create their own objects, like egui-ash-renderer).
    pub fn instance(&self) -> &ash::Instance {
        &self.instance
    }

    /// Waits until the device has nothing left to do.
    pub fn wait_idle(&self) -> Result<(), VkError> {
        // SAFETY: host access to the queue is not shared with another thread (every user
        // of the device is on the caller's thread).
        unsafe { self.device.device_wait_idle() }.map_err(vk_err("waiting for the device"))
    }

    /// Takes the validation messages gathered so far.
    pub fn take_messages(&self) -> Vec<String> {
        self.messages.lock().map(|mut v| std::mem::take(&mut *v)).unwrap_or_default()
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: every object created from this device holds an Arc to it, so none is
        // alive any more; wait for the GPU, then free in reverse creation order.
        unsafe {
            let _ = self.device.device_wait_idle();
            if let Ok(a) = self.allocator.lock() {
                a.report_memory_leaks(log::Level::Error);
            }
            ManuallyDrop::drop(&mut self.allocator);
            self.device.destroy_device(None);
            if let Some(sl) = &self.surface_loader {
                sl.destroy_surface(self.surface, None);
            }
            if let Some((l, m)) = &self.debug {
                l.destroy_debug_utils_messenger(*m, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

fn vk_err(what: &'static str) -> impl Fn(vk::Result) -> VkError {
    move |e| VkError::Vulkan { what, reason: format!("{e:?}") }
}

/// A buffer and its memory.
pub struct Buffer {
    dev: Arc<Device>,
    /// The Vulkan buffer.
    pub buffer: vk::Buffer,
    allocation: Option<Allocation>,
    /// Size, bytes.
    pub size: u64,
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
        Ok(Self { dev: dev.clone(), buffer, allocation: Some(allocation), size })
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
        // SAFETY: the owner waits for the GPU before dropping resources it used (the
        // solver waits after every submission).
        unsafe { self.dev.device.destroy_buffer(self.buffer, None) };
        if let (Some(a), Ok(mut alloc)) = (self.allocation.take(), self.dev.allocator.lock()) {
            let _ = alloc.free(a);
        }
    }
}

/// A device-local 2-D image and its view: the spring table read as texture memory, and
/// the renderer's targets, shadow map and fabric texture.
pub struct Image {
    dev: Arc<Device>,
    image: vk::Image,
    view: vk::ImageView,
    allocation: Option<Allocation>,
    /// Width, texels.
    pub width: u32,
    /// Height, texels.
    pub height: u32,
    /// Texel format.
    pub format: vk::Format,
    /// Colour or depth.
    pub aspect: vk::ImageAspectFlags,
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

    /// An image as `desc` says.
    pub fn with_desc(dev: &Arc<Device>, name: &str, desc: ImageDesc) -> Result<Self, VkError> {
        let ImageDesc { width, height, format, usage, samples } = desc;
        let aspect =
            if format == vk::Format::D32_SFLOAT { vk::ImageAspectFlags::DEPTH } else { vk::ImageAspectFlags::COLOR };
        if width == 0 || height == 0 || width > dev.max_image_2d || height > dev.max_image_2d {
            return Err(VkError::Vulkan {
                what: "creating an image",
                reason: format!("{width} × {height} texels; this device allows 1 … {} a side", dev.max_image_2d),
            });
        }
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D { width, height, depth: 1 })
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
            format,
            aspect,
        };
        // SAFETY: the allocation satisfies the image's requirements and is freed in Drop
        // after the image is destroyed.
        unsafe { d.bind_image_memory(image, allocation.memory(), allocation.offset()) }
            .map_err(vk_err("binding image memory"))?;
        me.allocation = Some(allocation);
        let view_info = vk::ImageViewCreateInfo::default()
            .image(image)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(format)
            .subresource_range(range(aspect));
        // SAFETY: the image is live and bound; the view is destroyed first in Drop.
        me.view = unsafe { d.create_image_view(&view_info, None) }.map_err(vk_err("creating an image view"))?;
        Ok(me)
    }
}

fn range(aspect: vk::ImageAspectFlags) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange::default().aspect_mask(aspect).level_count(1).layer_count(1)
}

impl Drop for Image {
    fn drop(&mut self) {
        // SAFETY: the owner waited for the GPU; view, image, memory in reverse order (a
        // null view is ignored by vkDestroyImageView).
        unsafe {
            self.dev.device.destroy_image_view(self.view, None);
            self.dev.device.destroy_image(self.image, None);
        }
        if let (Some(a), Ok(mut alloc)) = (self.allocation.take(), self.dev.allocator.lock()) {
            let _ = alloc.free(a);
        }
    }
}

/// A compute pipeline with its descriptor-set layout and pipeline layout.
pub struct Kernel {
    dev: Arc<Device>,
    set_layout: vk::DescriptorSetLayout,
    /// The pipeline layout (for binding sets and pushing constants).
    pub layout: vk::PipelineLayout,
    /// The pipeline.
    pub pipeline: vk::Pipeline,
}

impl Kernel {
    /// A pipeline for the SPIR-V `spirv` (entry `main`) with descriptor set 0 holding
    /// `bindings` and `push_size` bytes of push constants.
    pub fn new(
        dev: &Arc<Device>,
        spirv: &[u8],
        bindings: &[(u32, vk::DescriptorType)],
        push_size: u32,
    ) -> Result<Self, VkError> {
        if !spirv.len().is_multiple_of(4) {
            return Err(VkError::Vulkan { what: "loading SPIR-V", reason: "length not a multiple of 4".into() });
        }
        let words: Vec<u32> = spirv.chunks_exact(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
        let d = &dev.device;
        let b: Vec<vk::DescriptorSetLayoutBinding> = bindings
            .iter()
            .map(|&(binding, ty)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(binding)
                    .descriptor_type(ty)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        // SAFETY: valid device, create infos live across each call; each object is
        // destroyed in Drop (or below, on failure) before the device.
        unsafe {
            let set_layout = d
                .create_descriptor_set_layout(&vk::DescriptorSetLayoutCreateInfo::default().bindings(&b), None)
                .map_err(vk_err("creating a set layout"))?;
            let ranges =
                [vk::PushConstantRange::default().stage_flags(vk::ShaderStageFlags::COMPUTE).offset(0).size(push_size)];
            let set_layouts = [set_layout];
            let mut pl_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
            if push_size > 0 {
                pl_info = pl_info.push_constant_ranges(&ranges);
            }
            let layout = match d.create_pipeline_layout(&pl_info, None) {
                Ok(l) => l,
                Err(e) => {
                    d.destroy_descriptor_set_layout(set_layout, None);
                    return Err(vk_err("creating a pipeline layout")(e));
                }
            };
            let module = match d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None) {
                Ok(m) => m,
                Err(e) => {
                    d.destroy_pipeline_layout(layout, None);
                    d.destroy_descriptor_set_layout(set_layout, None);
                    return Err(vk_err("creating a shader module")(e));
                }
            };
            let stage = vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::COMPUTE)
                .module(module)
                .name(c"main");
            let info = [vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout)];
            let pipeline = d.create_compute_pipelines(vk::PipelineCache::null(), &info, None);
            d.destroy_shader_module(module, None);
            let pipeline = match pipeline {
                Ok(p) => p[0],
                Err((_, e)) => {
                    d.destroy_pipeline_layout(layout, None);
                    d.destroy_descriptor_set_layout(set_layout, None);
                    return Err(vk_err("creating a compute pipeline")(e));
                }
            };
            Ok(Self { dev: dev.clone(), set_layout, layout, pipeline })
        }
    }
}

impl Drop for Kernel {
    fn drop(&mut self) {
        // SAFETY: destroyed in reverse creation order after the owner waited for the GPU.
        unsafe {
            self.dev.device.destroy_pipeline(self.pipeline, None);
            self.dev.device.destroy_pipeline_layout(self.layout, None);
            self.dev.device.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

/// A descriptor pool with one set per (kernel, buffer assignment).
pub struct Sets {
    dev: Arc<Device>,
    pool: vk::DescriptorPool,
}

impl Sets {
    /// A pool for `max_sets` sets of at most 32 descriptors each.
    pub fn new(dev: &Arc<Device>, max_sets: u32) -> Result<Self, VkError> {
        let sizes = [
            vk::DescriptorPoolSize::default().ty(vk::DescriptorType::STORAGE_BUFFER).descriptor_count(32 * max_sets),
            vk::DescriptorPoolSize::default().ty(vk::DescriptorType::UNIFORM_BUFFER).descriptor_count(4 * max_sets),
            vk::DescriptorPoolSize::default().ty(vk::DescriptorType::SAMPLED_IMAGE).descriptor_count(2 * max_sets),
            vk::DescriptorPoolSize::default().ty(vk::DescriptorType::SAMPLER).descriptor_count(2 * max_sets),
        ];
        let info = vk::DescriptorPoolCreateInfo::default().max_sets(max_sets).pool_sizes(&sizes);
        // SAFETY: valid device and create info; destroyed in Drop.
        let pool =
            unsafe { dev.device.create_descriptor_pool(&info, None) }.map_err(vk_err("creating a descriptor pool"))?;
        Ok(Self { dev: dev.clone(), pool })
    }

    /// A set for `kernel` with `buffers[k]` (binding, type, buffer) bound whole, and
    /// `image` (binding, image) as a sampled image.
    pub fn allocate(
        &self,
        kernel: &Kernel,
        buffers: &[(u32, vk::DescriptorType, &Buffer)],
        image: Option<(u32, &Image)>,
    ) -> Result<vk::DescriptorSet, VkError> {
        let layouts = [kernel.set_layout];
        let info = vk::DescriptorSetAllocateInfo::default().descriptor_pool(self.pool).set_layouts(&layouts);
        // SAFETY: pool and layout belong to this device; the set lives as long as the pool.
        let set = unsafe { self.dev.device.allocate_descriptor_sets(&info) }
            .map_err(vk_err("allocating a descriptor set"))?[0];
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> = buffers
            .iter()
            .map(|(_, _, b)| [vk::DescriptorBufferInfo::default().buffer(b.buffer).offset(0).range(b.size)])
            .collect();
        let writes: Vec<vk::WriteDescriptorSet> = buffers
            .iter()
            .zip(&infos)
            .map(|((binding, ty, _), info)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(*binding)
                    .descriptor_type(*ty)
                    .buffer_info(info)
            })
            .collect();
        let image_info = image.map(|(_, img)| {
            [vk::DescriptorImageInfo::default()
                .image_view(img.view)
                .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)]
        });
        let mut writes = writes;
        if let (Some((binding, _)), Some(info)) = (image, &image_info) {
            writes.push(
                vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(binding)
                    .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                    .image_info(info),
            );
        }
        // SAFETY: the writes reference live buffers and the set just allocated.
        unsafe { self.dev.device.update_descriptor_sets(&writes, &[]) };
        Ok(set)
    }
}

impl Drop for Sets {
    fn drop(&mut self) {
        // SAFETY: the sets are no longer in use (the owner waited for the GPU).
        unsafe { self.dev.device.destroy_descriptor_pool(self.pool, None) };
    }
}

/// A ring of command buffers from one pool, a fence and a timestamp query pool. One
/// buffer is active (being recorded) at a time; a frame may record and submit several
/// (the naive recipe: one per substep) and wait once, on the last.
pub struct Commands {
    dev: Arc<Device>,
    pool: vk::CommandPool,
    cmds: Vec<vk::CommandBuffer>,
    active: usize,
    fence: vk::Fence,
    queries: vk::QueryPool,
    /// Capacity of the query pool.
    pub max_queries: u32,
}

/// One recorded dispatch.
pub struct Dispatch<'a> {
    /// The pipeline.
    pub kernel: &'a Kernel,
    /// Its descriptor set.
    pub set: vk::DescriptorSet,
    /// Push constants (may be empty).
    pub push: &'a [u8],
    /// Workgroups in x and y.
    pub groups: (u32, u32),
}

impl Commands {
    /// One command buffer on the device's queue family, with room for `max_queries`
    /// timestamps.
    pub fn new(dev: &Arc<Device>, max_queries: u32) -> Result<Self, VkError> {
        let d = &dev.device;
        // SAFETY: valid device and create infos; every object is destroyed in Drop.
        unsafe {
            let pool = d
                .create_command_pool(
                    &vk::CommandPoolCreateInfo::default()
                        .queue_family_index(dev.queue_family)
                        .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                    None,
                )
                .map_err(vk_err("creating a command pool"))?;
            let mut me = Self {
                dev: dev.clone(),
                pool,
                cmds: Vec::new(),
                active: 0,
                fence: vk::Fence::null(),
                queries: vk::QueryPool::null(),
                max_queries,
            };
            me.fence = d.create_fence(&vk::FenceCreateInfo::default(), None).map_err(vk_err("creating a fence"))?;
            if max_queries > 0 {
                me.queries = d
                    .create_query_pool(
                        &vk::QueryPoolCreateInfo::default()
                            .query_type(vk::QueryType::TIMESTAMP)
                            .query_count(max_queries),
                        None,
                    )
                    .map_err(vk_err("creating a query pool"))?;
            }
            me.reserve(1)?;
            Ok(me)
        }
    }

    /// Makes sure the ring has at least `count` command buffers.
    pub fn reserve(&mut self, count: usize) -> Result<(), VkError> {
        if count <= self.cmds.len() {
            return Ok(());
        }
        let info = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count((count - self.cmds.len()) as u32);
        // SAFETY: the pool belongs to this device; the buffers are freed in Drop.
        let more =
            unsafe { self.dev.device.allocate_command_buffers(&info) }.map_err(vk_err("allocating command buffers"))?;
        self.cmds.extend(more);
        Ok(())
    }

    pub(crate) fn cmd(&self) -> vk::CommandBuffer {
        self.cmds[self.active]
    }

    /// Starts recording buffer 0, resetting the first `query_count` queries (the previous
    /// submission must have completed).
    pub fn begin(&mut self, query_count: u32) -> Result<(), VkError> {
        self.begin_at(0, query_count)
    }

    /// Starts recording buffer `index` of the ring (reserved before), resetting the
    /// first `query_count` queries when not 0.
    pub fn begin_at(&mut self, index: usize, query_count: u32) -> Result<(), VkError> {
        self.reserve(index + 1)?;
        self.active = index;
        let d = &self.dev.device;
        // SAFETY: the command buffer is not pending (every frame waits on the fence,
        // which covers all earlier submissions, before recording again).
        unsafe {
            d.begin_command_buffer(
                self.cmd(),
                &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )
            .map_err(vk_err("beginning a command buffer"))?;
            if query_count > 0 {
                d.cmd_reset_query_pool(self.cmd(), self.queries, 0, query_count.min(self.max_queries));
            }
        }
        Ok(())
    }

    /// Records a timestamp into query `q` (below `max_queries`, reset by `begin`) once
    /// earlier compute work is done.
    pub fn timestamp(&self, q: u32) {
        if q >= self.max_queries {
            return;
        }
        let d = &self.dev.device;
        // SAFETY: recording state; `q` is below the pool's capacity (the caller checks)
        // and was reset in this frame. With synchronization2 the 1.3 entry point is used.
        unsafe {
            if self.dev.sync2 {
                d.cmd_write_timestamp2(self.cmd(), vk::PipelineStageFlags2::COMPUTE_SHADER, self.queries, q);
            } else {
                d.cmd_write_timestamp(self.cmd(), vk::PipelineStageFlags::COMPUTE_SHADER, self.queries, q);
            }
        }
    }

    /// Records a dispatch, with timestamps before and after it into queries `q`, `q + 1`
    /// when given.
    pub fn dispatch(&self, dsp: &Dispatch<'_>, timestamps: Option<u32>) {
        let d = &self.dev.device;
        if let Some(q) = timestamps {
            self.timestamp(q);
        }
        // SAFETY: recording state; pipeline, layout and set are live and compatible.
        unsafe {
            d.cmd_bind_pipeline(self.cmd(), vk::PipelineBindPoint::COMPUTE, dsp.kernel.pipeline);
            d.cmd_bind_descriptor_sets(
                self.cmd(),
                vk::PipelineBindPoint::COMPUTE,
                dsp.kernel.layout,
                0,
                &[dsp.set],
                &[],
            );
            if !dsp.push.is_empty() {
                d.cmd_push_constants(self.cmd(), dsp.kernel.layout, vk::ShaderStageFlags::COMPUTE, 0, dsp.push);
            }
            d.cmd_dispatch(self.cmd(), dsp.groups.0, dsp.groups.1, 1);
        }
        if let Some(q) = timestamps {
            self.timestamp(q + 1);
        }
    }

    /// A barrier making compute and transfer writes visible to later compute and transfer
    /// (a global memory barrier: the recipes' dependencies are whole buffers).
    pub fn barrier(&self) {
        self.compute_barrier(false);
    }

    /// The same after everything submitted before, at any stage (e.g. the renderer's
    /// vertex reads of the positions): the first barrier of a solver frame.
    pub fn barrier_after_all(&self) {
        self.compute_barrier(true);
    }

    fn compute_barrier(&self, after_all: bool) {
        let d = &self.dev.device;
        if self.dev.sync2 {
            let stages = vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::ALL_TRANSFER;
            let mb = [vk::MemoryBarrier2::default()
                .src_stage_mask(if after_all { vk::PipelineStageFlags2::ALL_COMMANDS } else { stages })
                .src_access_mask(vk::AccessFlags2::SHADER_STORAGE_WRITE | vk::AccessFlags2::TRANSFER_WRITE)
                .dst_stage_mask(stages)
                .dst_access_mask(
                    vk::AccessFlags2::SHADER_STORAGE_READ
                        | vk::AccessFlags2::SHADER_STORAGE_WRITE
                        | vk::AccessFlags2::TRANSFER_READ
                        | vk::AccessFlags2::TRANSFER_WRITE
                        | vk::AccessFlags2::UNIFORM_READ,
                )];
            // SAFETY: recording state; synchronization2 is enabled on this device.
            unsafe { d.cmd_pipeline_barrier2(self.cmd(), &vk::DependencyInfo::default().memory_barriers(&mb)) };
            return;
        }
        let mb = [vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE)
            .dst_access_mask(
                vk::AccessFlags::SHADER_READ
                    | vk::AccessFlags::SHADER_WRITE
                    | vk::AccessFlags::TRANSFER_READ
                    | vk::AccessFlags::TRANSFER_WRITE
                    | vk::AccessFlags::UNIFORM_READ,
            )];
        let stages = vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER;
        let src = if after_all { vk::PipelineStageFlags::ALL_COMMANDS } else { stages };
        // SAFETY: recording state.
        unsafe { d.cmd_pipeline_barrier(self.cmd(), src, stages, vk::DependencyFlags::empty(), &mb, &[], &[]) };
    }

    /// Records a copy of `size` bytes from `src` at `src_offset` to `dst` at `dst_offset`.
    pub fn copy_range(&self, src: &Buffer, src_offset: u64, dst: &Buffer, dst_offset: u64, size: u64) {
        let region = [vk::BufferCopy::default().src_offset(src_offset).dst_offset(dst_offset).size(size)];
        // SAFETY: recording state; both buffers are live and the ranges lie within them
        // (the callers size them).
        unsafe { self.dev.device.cmd_copy_buffer(self.cmd(), src.buffer, dst.buffer, &region) };
    }

    /// Records a copy of `size` bytes from `src` to `dst`.
    pub fn copy(&self, src: &Buffer, dst: &Buffer, size: u64) {
        self.copy_range(src, 0, dst, 0, size);
    }

    /// Records the upload of a whole image from `src` (tightly packed texels): layout to
    /// transfer destination, copy, layout to shader-read-only for compute.
    pub fn copy_to_image(&self, src: &Buffer, dst: &Image) {
        let d = &self.dev.device;
        let to_dst = [vk::ImageMemoryBarrier::default()
            .old_layout(vk::ImageLayout::UNDEFINED)
            .new_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
            .dst_access_mask(vk::AccessFlags::TRANSFER_WRITE)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(dst.image)
            .subresource_range(range(dst.aspect))];
        let to_read = [vk::ImageMemoryBarrier::default()
            .old_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
            .new_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)
            .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
            .dst_access_mask(vk::AccessFlags::SHADER_READ)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(dst.image)
            .subresource_range(range(dst.aspect))];
        let region = [vk::BufferImageCopy::default()
            .image_subresource(
                vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1),
            )
            .image_extent(vk::Extent3D { width: dst.width, height: dst.height, depth: 1 })];
        // SAFETY: recording state; `src` holds width × height texels (the caller sizes it);
        // the image is live and only used by this command buffer until the barrier.
        unsafe {
            d.cmd_pipeline_barrier(
                self.cmd(),
                vk::PipelineStageFlags::ALL_COMMANDS,
                vk::PipelineStageFlags::TRANSFER,
                vk::DependencyFlags::empty(),
                &[],
                &[],
                &to_dst,
            );
            d.cmd_copy_buffer_to_image(
                self.cmd(),
                src.buffer,
                dst.image,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &region,
            );
            d.cmd_pipeline_barrier(
                self.cmd(),
                vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::FRAGMENT_SHADER,
                vk::DependencyFlags::empty(),
                &[],
                &[],
                &to_read,
            );
        }
    }

    /// Records a fill of `dst` with zeros.
    pub fn zero(&self, dst: &Buffer) {
        // SAFETY: recording state; the buffer is live and has TRANSFER_DST usage.
        unsafe { self.dev.device.cmd_fill_buffer(self.cmd(), dst.buffer, 0, vk::WHOLE_SIZE, 0) };
    }

    /// Ends the active buffer and submits it; with `fence`, the fence is signalled once it
    /// and every earlier submission on the queue are done (wait with [`Commands::wait`]).
    pub fn submit(&self, fence: bool) -> Result<(), VkError> {
        let d = &self.dev.device;
        // SAFETY: the buffer is in recording state; the fence is unsignalled (every
        // fenced submit is waited for and the fence reset before the next).
        unsafe {
            d.end_command_buffer(self.cmd()).map_err(vk_err("ending a command buffer"))?;
            let cmds = [self.cmd()];
            let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
            let f = if fence { self.fence } else { vk::Fence::null() };
            d.queue_submit(self.dev.queue, &submit, f).map_err(vk_err("submitting"))
        }
    }

    /// Waits for the fenced submission (and so for all before it); returns `query_count`
    /// timestamps in ticks.
    pub fn wait(&self, query_count: u32) -> Result<Vec<u64>, VkError> {
        let d = &self.dev.device;
        // SAFETY: a fenced submission is pending; after the wait nothing recorded is
        // pending, so the fence can be reset and the queries read.
        unsafe {
            d.wait_for_fences(&[self.fence], true, u64::MAX).map_err(vk_err("waiting for the GPU"))?;
            d.reset_fences(&[self.fence]).map_err(vk_err("resetting a fence"))?;
            let mut ticks = vec![0u64; query_count.min(self.max_queries) as usize];
            if !ticks.is_empty() {
                d.get_query_pool_results(
                    self.queries,
                    0,
                    &mut ticks,
                    vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                )
                .map_err(vk_err("reading timestamps"))?;
            }
            Ok(ticks)
        }
    }

    /// Ends, submits and waits; returns `query_count` timestamps in ticks.
    pub fn submit_and_wait(&self, query_count: u32) -> Result<Vec<u64>, VkError> {
        self.submit(true)?;
        self.wait(query_count)
    }
}

impl Drop for Commands {
    fn drop(&mut self) {
        // SAFETY: every submission was waited for; destroy in reverse creation order (null
        // handles, after a failed creation, are ignored).
        unsafe {
            self.dev.device.destroy_query_pool(self.queries, None);
            self.dev.device.destroy_fence(self.fence, None);
            if !self.cmds.is_empty() {
                self.dev.device.free_command_buffers(self.pool, &self.cmds);
            }
            self.dev.device.destroy_command_pool(self.pool, None);
        }
    }
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
