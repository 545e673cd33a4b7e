//! The instance, the device, its queue and allocator, and the validation layer's messages.

use std::ffi::{CStr, c_void};
use std::mem::ManuallyDrop;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, OnceLock};

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use super::vk_err;
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
    pub(super) _entry: ash::Entry,
    pub(super) instance: ash::Instance,
    pub(super) debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
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
    pub(super) allocator: ManuallyDrop<Mutex<Allocator>>,
    /// Held for every use of the queue (submit, present, wait idle): Vulkan asks the host
    /// to synchronise them, and objects may be dropped on any thread.
    pub(super) queue_lock: Mutex<()>,
    /// Objects destroyed so far (a recording made before a destruction is not submitted).
    pub(super) destroyed: AtomicU64,
    /// Adapter name.
    pub name: String,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period: f32,
    /// Whether the queue writes timestamps.
    pub timestamps: bool,
    /// Largest push-constant block, bytes.
    pub max_push_constants: u32,
    /// Largest workgroup (shared) memory of a compute shader, bytes.
    pub max_shared_memory: u32,
    /// `atomicAdd` on `f32` in storage buffers (VK_EXT_shader_atomic_float), enabled.
    pub float_atomics: bool,
    /// Largest storage-buffer binding, bytes.
    pub max_storage_range: u64,
    /// Invocations per subgroup (0 when unknown).
    pub subgroup_size: u32,
    /// Subgroup arithmetic (subgroupAdd, subgroupMax) in compute shaders.
    pub subgroup_arithmetic: bool,
    /// Relative subgroup shuffles (subgroupShuffleUp/Down) besides the arithmetic.
    pub subgroup_shuffle: bool,
    /// The device runs on the CPU (`VK_PHYSICAL_DEVICE_TYPE_CPU`: lavapipe, SwiftShader).
    pub cpu: bool,
    /// synchronization2 (Vulkan 1.3) enabled: timestamps by `vkCmdWriteTimestamp2`,
    /// barriers by `vkCmdPipelineBarrier2`.
    pub sync2: bool,
    /// Largest 2-D image side, texels.
    pub max_image_2d: u32,
    /// The largest side of a 3-D image, texels.
    pub max_image_3d: u32,
    /// `R32_SFLOAT` images can be sampled with linear filtering (the bodies' distance
    /// fields as an image, `sdf=image`).
    pub r32f_linear: bool,
    /// Bits of a filtered sample's fractional weights (`subTexelPrecisionBits`).
    pub sub_texel_bits: u32,
    /// The queue draws too, with dynamic rendering (Vulkan 1.3): the renderer can run.
    pub dynamic_rendering: bool,
    /// The window's surface (null without a window).
    pub surface: vk::SurfaceKHR,
    /// Surface queries (with a window).
    pub surface_loader: Option<ash::khr::surface::Instance>,
    /// Swapchain functions (with a window).
    pub swapchain_loader: Option<ash::khr::swapchain::Device>,
}

/// The system's Vulkan loader, loaded once per process and never unloaded.
///
/// Each `Device` used to load (`dlopen`) its own: when the last one of a process was
/// dropped, the loader was unloaded and with it the driver (lavapipe and LLVM) and the
/// validation layer, all loaded again by the next `Device`. Test binaries, whose tests
/// make and drop devices from two threads, did that dozens of times a run, and twice in
/// ~60 CI runs one died with SIGSEGV while doing it (docs/testing.md, "The crash that was
/// seen once"). One loader for the process is also what an application does.
fn loader() -> Result<ash::Entry, VkError> {
    static LOADER: OnceLock<Result<ash::Entry, String>> = OnceLock::new();
    LOADER
        .get_or_init(|| {
            // SAFETY: loading the system's Vulkan loader; it is kept in this static for the
            // rest of the process (never unloaded), and every Device holds a clone of it.
            unsafe { ash::Entry::load() }.map_err(|e| e.to_string())
        })
        .clone()
        .map_err(VkError::NoVulkan)
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
        let entry = loader()?;
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
        let subgroup_shuffle =
            subgroup_arithmetic && subgroup.supported_operations.contains(vk::SubgroupFeatureFlags::SHUFFLE_RELATIVE);
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
        // SAFETY: `physical` is a device of this instance.
        let r32f = unsafe { instance.get_physical_device_format_properties(physical, vk::Format::R32_SFLOAT) };
        let r32f_linear = r32f.optimal_tiling_features.contains(vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR);
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
            queue_lock: Mutex::new(()),
            destroyed: AtomicU64::new(0),
            name,
            timestamp_period: props.limits.timestamp_period,
            timestamps: timestamps && props.limits.timestamp_compute_and_graphics == vk::TRUE,
            max_push_constants: props.limits.max_push_constants_size,
            max_shared_memory: props.limits.max_compute_shared_memory_size,
            float_atomics,
            max_storage_range: props.limits.max_storage_buffer_range as u64,
            subgroup_size: subgroup.subgroup_size,
            subgroup_arithmetic,
            subgroup_shuffle,
            cpu: props.device_type == vk::PhysicalDeviceType::CPU,
            sync2,
            max_image_2d: props.limits.max_image_dimension2_d,
            max_image_3d: props.limits.max_image_dimension3_d,
            r32f_linear,
            sub_texel_bits: props.limits.sub_texel_precision_bits,
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
        let _queue = self.queue();
        // SAFETY: the queue lock is held, so no other thread uses the queue meanwhile.
        unsafe { self.device.device_wait_idle() }.map_err(vk_err("waiting for the device"))
    }

    /// The queue, held (see `queue_lock`).
    pub(super) fn queue(&self) -> MutexGuard<'_, ()> {
        self.queue_lock.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Destroys an object: once the device is idle (no submitted work can use it any
    /// more), with the queue held, and counted, so that a recording made before is
    /// refused at submission.
    pub(super) fn retire(&self, destroy: impl FnOnce(&ash::Device)) {
        let _queue = self.queue();
        // SAFETY: the queue lock is held; waiting for idle has no other precondition. An
        // error (device lost) leaves nothing pending either.
        let _ = unsafe { self.device.device_wait_idle() };
        destroy(&self.device);
        self.destroyed.fetch_add(1, Ordering::SeqCst);
    }

    /// Objects destroyed so far.
    pub(super) fn destroyed(&self) -> u64 {
        self.destroyed.load(Ordering::SeqCst)
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

/// Whether an object is still alive: shared with the descriptor sets that point at it, so
/// that a set whose buffer, image or pool was dropped is refused when bound.
#[derive(Debug, Clone)]
pub struct Alive(Arc<AtomicBool>);

impl Alive {
    pub(super) fn new() -> Self {
        Self(Arc::new(AtomicBool::new(true)))
    }

    pub(super) fn get(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }

    pub(super) fn end(&self) {
        self.0.store(false, Ordering::SeqCst);
    }
}
