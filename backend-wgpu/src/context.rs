//! Adapter and device: found once, shared by solvers (and later renderers).

use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Mutex};

use thiserror::Error;

/// Why the GPU could not be used.
#[derive(Debug, Error)]
pub enum GpuError {
    /// No adapter at all.
    #[error(
        "no GPU adapter found (wgpu: Vulkan, or GL with --wgpu-backend gl); on Linux, `apt-get install mesa-vulkan-drivers` gives a software one (lavapipe)"
    )]
    NoAdapter,
    /// The adapter refused the device we asked for.
    #[error("cannot open a device on {adapter}: {reason}")]
    Device {
        /// Adapter name.
        adapter: String,
        /// wgpu's reason.
        reason: String,
    },
    /// A wgpu validation or out-of-memory error during the named operation.
    #[error("wgpu error during {what}: {reason}")]
    Wgpu {
        /// What was being done.
        what: &'static str,
        /// wgpu's message.
        reason: String,
    },
    /// Mapping a buffer for reading failed.
    #[error("reading back from the GPU failed: {0}")]
    Readback(String),
}

/// The backends chosen by [`choose_backends`] (0: none chosen).
static CHOSEN: AtomicU32 = AtomicU32::new(0);

/// Which of wgpu's own backends every context made from now on may use — the app's
/// `--wgpu-backend vulkan|gl`, so that wgpu-on-GL can stand beside raw GL as
/// wgpu-on-Vulkan stands beside raw Vulkan. Without a call: what wgpu prefers (the
/// `WGPU_BACKEND` environment variable, else every backend but GL: Vulkan, Metal, DX12).
pub fn choose_backends(backends: wgpu::Backends) {
    CHOSEN.store(backends.bits(), Ordering::Relaxed);
}

/// The backends chosen, if any.
pub fn chosen_backends() -> Option<wgpu::Backends> {
    Some(wgpu::Backends::from_bits_truncate(CHOSEN.load(Ordering::Relaxed))).filter(|b| !b.is_empty())
}

fn with_chosen(mut d: wgpu::InstanceDescriptor) -> wgpu::InstanceDescriptor {
    // Unchosen: wgpu's primary backends (Vulkan here), as before clothlab built wgpu's GL
    // backend too. wgpu's GL instance terminates the EGL display it shares with raw GL
    // contexts when it drops (wgpu-hal counts only its own users), so it is made only when
    // asked for; clothlab-gl opens its displays through EGL_EXT_platform_device where it
    // can, apart from wgpu's.
    d.backends = match chosen_backends() {
        Some(b) => b,
        None if std::env::var_os("WGPU_BACKEND").is_some() => d.backends,
        None => d.backends & !wgpu::Backends::GL,
    };
    d
}

/// An adapter, its device and queue, and what they can do. Clones share the device.
#[derive(Clone)]
pub struct GpuContext {
    /// The adapter.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Adapter name, driver and backend, for reports.
    pub info: wgpu::AdapterInfo,
    /// Timestamp queries are available.
    pub timestamps: bool,
    /// `atomic<f32>` with `atomicAdd` in storage buffers is available.
    pub float_atomics: bool,
    /// Immediates (push constants) big enough for the step constants are available.
    pub immediates: bool,
    /// Subgroup operations in compute shaders (`Features::SUBGROUP`) are available.
    pub subgroups: bool,
    /// 32-bit float textures can be sampled with filtering (`Features::FLOAT32_FILTERABLE`:
    /// the bodies' distance fields as an image, `sdf=image`).
    pub float32_filterable: bool,
    /// Errors wgpu reported outside an error scope, oldest first.
    uncaptured: Arc<Mutex<Vec<String>>>,
}

impl GpuContext {
    /// Opens the first adapter wgpu finds (high performance preferred), with every limit
    /// the adapter has and timestamp queries if it supports them.
    pub fn new() -> Result<Self, GpuError> {
        let instance =
            wgpu::Instance::new(with_chosen(wgpu::InstanceDescriptor::new_without_display_handle_from_env()));
        Self::open(&instance, None)
    }

    /// Like [`GpuContext::new`], on one of `backends` only, whatever was chosen (the
    /// bench measures wgpu on GL beside wgpu on Vulkan in one run).
    pub fn with_backends(backends: wgpu::Backends) -> Result<Self, GpuError> {
        let mut d = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        d.backends = backends;
        Self::open(&wgpu::Instance::new(d), None)
    }

    /// Like [`GpuContext::new`], with an adapter that can present to `window`, and the
    /// window's surface (not configured yet).
    pub fn for_window<W>(window: std::sync::Arc<W>) -> Result<(Self, wgpu::Surface<'static>), GpuError>
    where
        W: raw_window_handle::HasWindowHandle
            + raw_window_handle::HasDisplayHandle
            + std::fmt::Debug
            + Send
            + Sync
            + 'static,
    {
        let instance = wgpu::Instance::new(with_chosen(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
            Box::new(window.clone()),
        )));
        let surface = match instance.create_surface(window) {
            Ok(s) => s,
            // No backend could make a surface: most likely there is no adapter at all.
            Err(e) => {
                Self::open(&instance, None)?;
                return Err(GpuError::Wgpu { what: "creating the window surface", reason: e.to_string() });
            }
        };
        let ctx = Self::open(&instance, Some(&surface))?;
        Ok((ctx, surface))
    }

    fn open(instance: &wgpu::Instance, surface: Option<&wgpu::Surface<'_>>) -> Result<Self, GpuError> {
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            compatible_surface: surface,
            ..Default::default()
        }))
        .map_err(|_| GpuError::NoAdapter)?;
        let info = adapter.get_info();
        let timestamps = adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        let mut required_features = wgpu::Features::empty();
        if timestamps {
            required_features |= wgpu::Features::TIMESTAMP_QUERY;
        }
        let immediates = adapter.features().contains(wgpu::Features::IMMEDIATES)
            && adapter.limits().max_immediate_size as usize >= clothlab_core::StepParams::GPU_BYTES;
        if immediates {
            required_features |= wgpu::Features::IMMEDIATES;
        }
        let float_atomics = adapter.features().contains(wgpu::Features::SHADER_FLOAT32_ATOMIC);
        if float_atomics {
            required_features |= wgpu::Features::SHADER_FLOAT32_ATOMIC;
        }
        let subgroups = adapter.features().contains(wgpu::Features::SUBGROUP);
        if subgroups {
            required_features |= wgpu::Features::SUBGROUP;
        }
        let float32_filterable = adapter.features().contains(wgpu::Features::FLOAT32_FILTERABLE);
        if float32_filterable {
            required_features |= wgpu::Features::FLOAT32_FILTERABLE;
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("clothlab"),
            required_features,
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device { adapter: info.name.clone(), reason: e.to_string() })?;
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let sink = uncaptured.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            // Surfaced by `check` as the caller's error; logged here for RUST_LOG=debug.
            log::debug!("wgpu: {e}");
            if let Ok(mut v) = sink.lock() {
                v.push(e.to_string());
            }
        }));
        log::info!("wgpu adapter: {} ({:?}, {})", info.name, info.backend, info.driver_info);
        Ok(Self {
            adapter,
            device,
            queue,
            info,
            timestamps,
            float_atomics,
            immediates,
            subgroups,
            float32_filterable,
            uncaptured,
        })
    }

    /// One line naming the adapter: `llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan, Mesa 22.3.6)`.
    pub fn describe(&self) -> String {
        format!("{} ({:?}, {} {})", self.info.name, self.info.backend, self.info.driver, self.info.driver_info)
    }

    /// Fails with the first error wgpu reported since the last call, if any.
    pub fn check(&self, what: &'static str) -> Result<(), GpuError> {
        let mut v = self.uncaptured.lock().map_err(|_| GpuError::Wgpu { what, reason: "poisoned lock".into() })?;
        if v.is_empty() {
            return Ok(());
        }
        let reason = v.remove(0);
        v.clear();
        Err(GpuError::Wgpu { what, reason })
    }

    /// Blocks until the queue is idle.
    pub fn wait_idle(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| GpuError::Wgpu { what: "waiting for the GPU", reason: e.to_string() })
    }

    /// Copies `size` bytes of `src` from `offset` into a mapped staging buffer and returns them.
    pub fn read_buffer(&self, src: &wgpu::Buffer, offset: u64, size: u64) -> Result<Vec<u8>, GpuError> {
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("readback") });
        enc.copy_buffer_to_buffer(src, offset, &staging, 0, size);
        self.queue.submit([enc.finish()]);
        let slice = staging.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.wait_idle()?;
        rx.recv().map_err(|e| GpuError::Readback(e.to_string()))?.map_err(|e| GpuError::Readback(e.to_string()))?;
        let data = slice.get_mapped_range().map_err(|e| GpuError::Readback(e.to_string()))?.to_vec();
        staging.unmap();
        Ok(data)
    }
}
