//! The Vulkan engine: device-local buffers filled through a staging buffer, one pipeline
//! and two descriptor sets (one per position parity) per kernel, a ring of command buffers
//! (one per submission of a frame: the naive recipe submits each substep without waiting),
//! a global memory barrier wherever the generic solver says the data needs one, push
//! constants, timestamps, and the spring table as a sampled image on request. The solver
//! itself is [`clothlab_engine::GpuSolver`]: [`VulkanSolver`] is it on this engine.

use std::collections::HashMap;
use std::sync::Arc;

use ash::vk;
use clothlab_core::layout::{BindKind, Buf, TABLE_WIDTH};
use clothlab_core::solver::SolverError;
use clothlab_engine::gpu::{BufferId, Dispatch, Engine, EngineInfo, Finished};
use clothlab_engine::kernels::KernelRef;
use clothlab_engine::solver::MAX_QUERIES;
use clothlab_engine::{GpuSolver, SolverOptions, VariantSpec};
use gpu_allocator::MemoryLocation;

use crate::VkError;
use crate::raw::{self, Buffer, Commands, Device, Image, Kernel, Set, Sets};

/// The cloth solver on raw Vulkan.
pub type VulkanSolver = GpuSolver<VulkanEngine>;

/// Sets the descriptor pool holds: two per kernel, for the built-in kernels in every
/// flavor and the kernels added from outside.
const MAX_KERNELS: u32 = 384;
/// Alignment of the pieces of a frame in the staging buffer (constants, readbacks).
const STAGING_ALIGN: u64 = 256;
/// The staging room a frame's recorded writes and readbacks may use.
const FRAME_STAGING: u64 = 64 * 1024;

fn backend(e: VkError) -> SolverError {
    match e {
        VkError::NoVulkan(_) | VkError::NoAdapter => SolverError::NoAdapter(e.to_string()),
        e => SolverError::Driver(e.to_string()),
    }
}

/// The API's part of the Vulkan solver.
pub struct VulkanEngine {
    info: EngineInfo,
    subgroup_size: u32,
    sync2: bool,
    bindings: [Vec<(u32, vk::DescriptorType, BufferId)>; 2],
    // Vulkan objects; each holds the device alive, and is dropped before it.
    kernels: HashMap<KernelRef, (Kernel, [Set; 2])>,
    sets: Sets,
    cmds: Commands,
    staging: Buffer,
    /// Where the next recorded write or readback goes in `staging` (reset by every wait).
    cursor: u64,
    /// Recorded writes past `staging`'s frame room (a moving scene writes its colliders
    /// before every substep: four arrays a substep, 64 KiB at 64 substeps): chunks kept
    /// and reused, filled from the start after every wait.
    chunks: Vec<Buffer>,
    /// The chunk being filled and where in it (reset by every wait).
    chunk_at: (usize, u64),
    /// Readbacks recorded since the last wait: (offset in staging, size).
    readbacks: Vec<(u64, u64)>,
    table: Option<Image>,
    /// The bodies' distance fields as a 3-D image and its trilinear sampler (`sdf=image`).
    sdf: Option<(Image, raw::Sampler)>,
    buffers: Vec<Buffer>,
    dev: Arc<Device>,
}

impl VulkanEngine {
    /// Opens the first Vulkan device with a compute queue; with `validation`, the Khronos
    /// validation layer checks every call (when installed).
    pub fn new(validation: bool) -> Result<Self, SolverError> {
        Self::on_device(&crate::Device::new(validation).map_err(backend)?)
    }

    /// An engine on `dev` (a window's device: the presenter draws the solver's buffers).
    pub fn on_device(dev: &crate::Device) -> Result<Self, SolverError> {
        let dev = dev.raw().clone();
        let info = EngineInfo {
            api: "vulkan",
            adapter: dev.name.clone(),
            float_atomics: dev.float_atomics,
            // 128 bytes is the Vulkan minimum, so always in practice.
            immediates: dev.max_push_constants as usize >= clothlab_core::StepParams::GPU_BYTES,
            timestamps: dev.timestamps,
            timestamp_period_ns: dev.timestamp_period as f64,
            max_binding: dev.max_storage_range,
            subgroup_arithmetic: dev.subgroup_arithmetic,
            subgroup_shuffle: dev.subgroup_shuffle,
            cpu: dev.cpu,
            table_image: true,
            sdf_image: dev.r32f_linear,
            workgroup_memory: dev.max_shared_memory,
        };
        let usage = vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
        let staging = Buffer::new(&dev, "staging", FRAME_STAGING, usage, MemoryLocation::CpuToGpu).map_err(backend)?;
        Ok(Self {
            info,
            subgroup_size: dev.subgroup_size,
            sync2: dev.sync2,
            bindings: [Vec::new(), Vec::new()],
            kernels: HashMap::new(),
            sets: Sets::new(&dev, 2 * MAX_KERNELS).map_err(backend)?,
            cmds: Commands::new(&dev, MAX_QUERIES).map_err(backend)?,
            staging,
            cursor: 0,
            chunks: Vec::new(),
            chunk_at: (0, 0),
            readbacks: Vec::new(),
            table: None,
            sdf: None,
            buffers: Vec::new(),
            dev,
        })
    }

    /// The device (for the renderer, the presenter and checks that outlive the solver).
    pub fn device(&self) -> crate::Device {
        crate::Device::from_raw(&self.dev)
    }

    /// Validation-layer messages gathered since the last call (none when it is off).
    pub fn take_validation_messages(&self) -> Vec<String> {
        self.dev.take_messages()
    }

    /// Invocations per subgroup on this device (0 when unknown).
    pub fn subgroup_size(&self) -> u32 {
        self.subgroup_size
    }

    /// Whether timestamps and barriers use synchronization2 (Vulkan 1.3).
    pub fn sync2(&self) -> bool {
        self.sync2
    }

    /// A staging buffer of at least `size` bytes (grown while nothing is pending).
    fn staging(&mut self, size: u64) -> Result<&mut Buffer, SolverError> {
        if self.staging.size < size {
            let usage = vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
            let size = size.max(FRAME_STAGING);
            self.staging = Buffer::new(&self.dev, "staging", size, usage, MemoryLocation::CpuToGpu).map_err(backend)?;
        }
        Ok(&mut self.staging)
    }

    /// Room for `size` bytes of this frame in the staging buffer; its offset.
    fn frame_room(&mut self, size: u64) -> Result<u64, SolverError> {
        let at = self.cursor.next_multiple_of(STAGING_ALIGN);
        if at + size > self.staging.size.min(FRAME_STAGING) {
            return Err(SolverError::Driver(format!(
                "a frame's constants and readbacks exceed the {FRAME_STAGING} bytes of staging set aside for them"
            )));
        }
        self.cursor = at + size;
        Ok(at)
    }

    fn buf(&self, id: BufferId) -> Result<&Buffer, SolverError> {
        self.buffers.get(id.0 as usize).ok_or_else(|| SolverError::Invalid(format!("no Vulkan buffer {}", id.0)))
    }
}

/// The descriptor type of a binding.
fn descriptor(kind: BindKind) -> vk::DescriptorType {
    match kind {
        BindKind::Uniform => vk::DescriptorType::UNIFORM_BUFFER,
        BindKind::Storage => vk::DescriptorType::STORAGE_BUFFER,
        BindKind::Image | BindKind::Volume => vk::DescriptorType::SAMPLED_IMAGE,
        BindKind::Sampler => vk::DescriptorType::SAMPLER,
    }
}

impl Engine for VulkanEngine {
    type Buffer = Buffer;

    fn info(&self) -> &EngineInfo {
        &self.info
    }

    fn create_buffer(&mut self, buf: Buf, label: &str, contents: &[u8], vertex: bool) -> Result<BufferId, SolverError> {
        let usage = match buf.kind() {
            BindKind::Uniform => vk::BufferUsageFlags::UNIFORM_BUFFER,
            _ => vk::BufferUsageFlags::STORAGE_BUFFER,
        } | if vertex { vk::BufferUsageFlags::VERTEX_BUFFER } else { vk::BufferUsageFlags::empty() }
            | vk::BufferUsageFlags::TRANSFER_DST
            | vk::BufferUsageFlags::TRANSFER_SRC;
        let b =
            Buffer::new(&self.dev, label, contents.len() as u64, usage, MemoryLocation::GpuOnly).map_err(backend)?;
        self.buffers.push(b);
        let id = BufferId(self.buffers.len() as u32 - 1);
        self.write(id, contents)?;
        Ok(id)
    }

    fn buffer(&self, id: BufferId) -> &Buffer {
        &self.buffers[id.0 as usize]
    }

    fn set_table_image(&mut self, texels: &[[u32; 4]], height: u32) -> Result<(), SolverError> {
        let max = self.dev.max_image_2d;
        if height > max {
            return Err(SolverError::Unsupported(format!(
                "table=image: this grid's spring table needs a {TABLE_WIDTH}×{height} image, taller than the {max} texels {} allows; use table=storage or table=uniform",
                self.info.adapter
            )));
        }
        if self.table.as_ref().is_none_or(|t| t.height != height) {
            if !self.kernels.is_empty() {
                return Err(SolverError::Invalid("the spring-table image cannot change size once bound".into()));
            }
            self.table = Some(Image::new(&self.dev, "spring table", TABLE_WIDTH, height).map_err(backend)?);
        }
        let bytes: &[u8] = bytemuck::cast_slice(texels);
        let map = self
            .staging(bytes.len() as u64)?
            .mapped()
            .ok_or_else(|| SolverError::Driver("staging not host visible".into()))?;
        map[..bytes.len()].copy_from_slice(bytes);
        let image = self.table.as_ref().expect("made above");
        self.cmds.begin(0).map_err(backend)?;
        self.cmds.copy_to_image(&self.staging, image);
        self.cmds.submit_and_wait(0).map_err(backend)?;
        Ok(())
    }

    /// The fields as an `R32_SFLOAT` 3-D image (the thesis's texture memory, where the
    /// hardware interpolates), uploaded once through the staging buffer; a trilinear
    /// sampler clamped to the edge.
    fn set_sdf_image(&mut self, values: &[f32], dims: [u32; 3]) -> Result<(), SolverError> {
        let [w, h, d] = dims;
        if !self.info.sdf_image {
            return Err(SolverError::Unsupported(format!(
                "sdf=image: {} cannot filter R32_SFLOAT images; use sdf=storage",
                self.info.adapter
            )));
        }
        if values.len() != (w * h * d) as usize {
            return Err(SolverError::Invalid(format!("{} values for a {w}×{h}×{d} image", values.len())));
        }
        if !self.kernels.is_empty() || self.sdf.is_some() {
            return Err(SolverError::Invalid("the distance-field image is made once, before any kernel".into()));
        }
        let image = Image::volume(&self.dev, "distance fields", w, h, d)
            .map_err(|e| SolverError::Unsupported(format!("sdf=image: {e}; use sdf=storage")))?;
        let sampler = raw::Sampler::clamped(&self.dev).map_err(backend)?;
        let bytes: &[u8] = bytemuck::cast_slice(values);
        let map = self
            .staging(bytes.len() as u64)?
            .mapped()
            .ok_or_else(|| SolverError::Driver("staging not host visible".into()))?;
        map[..bytes.len()].copy_from_slice(bytes);
        self.cmds.begin(0).map_err(backend)?;
        self.cmds.copy_to_image(&self.staging, &image);
        self.cmds.submit_and_wait(0).map_err(backend)?;
        self.sdf = Some((image, sampler));
        Ok(())
    }

    fn bind(&mut self, sets: [Vec<(Buf, BufferId)>; 2]) -> Result<(), SolverError> {
        for (k, set) in sets.into_iter().enumerate() {
            self.bindings[k] = set.into_iter().map(|(b, id)| (b.binding(), descriptor(b.kind()), id)).collect();
        }
        Ok(())
    }

    fn build(&mut self, k: KernelRef, immediates: u32) -> Result<(), SolverError> {
        if self.kernels.contains_key(&k) {
            return Ok(());
        }
        if self.kernels.len() as u32 >= MAX_KERNELS {
            return Err(SolverError::Shader {
                kernel: k.shader_name(),
                reason: format!("at most {MAX_KERNELS} kernels fit a Vulkan solver"),
            });
        }
        let spirv = k.spirv()?;
        // Only the buffers its row reads or writes (a second home of their data counts
        // as the data): a layout of every binding would pass lavapipe's 32 storage
        // buffers a stage.
        let used = |b: u32| {
            Buf::from_binding(b).is_some_and(|buf| k.def.reads.iter().chain(k.def.writes).any(|&r| r == buf.data()))
        };
        let mut layout: Vec<(u32, vk::DescriptorType)> =
            self.bindings[0].iter().filter(|(b, ..)| used(*b)).map(|(b, t, _)| (*b, *t)).collect();
        let image = match (&self.table, k.flavor.table_image) {
            (Some(i), true) => Some((Buf::Table.binding(), i)),
            (None, true) => {
                return Err(SolverError::Shader {
                    kernel: k.shader_name(),
                    reason: "built without the table image".into(),
                });
            }
            _ => None,
        };
        let mut images: Vec<(u32, &Image)> = image.into_iter().collect();
        let mut sampler = None;
        if k.flavor.sdf_image {
            let (img, smp) = self.sdf.as_ref().ok_or_else(|| SolverError::Shader {
                kernel: k.shader_name(),
                reason: "built without the distance-field image".into(),
            })?;
            images.push((Buf::SdfImage.binding(), img));
            sampler = Some((Buf::SdfSampler.binding(), smp));
        }
        for &(b, _) in &images {
            layout.push((b, vk::DescriptorType::SAMPLED_IMAGE));
        }
        if let Some((b, _)) = sampler {
            layout.push((b, descriptor(BindKind::Sampler)));
        }
        let kernel = Kernel::new(&self.dev, &spirv, &layout, immediates).map_err(backend)?;
        let set = |parity: usize| {
            let bound: Vec<(u32, vk::DescriptorType, &Buffer)> = self.bindings[parity]
                .iter()
                .filter(|(b, ..)| used(*b))
                .map(|&(b, t, id)| (b, t, &self.buffers[id.0 as usize]))
                .collect();
            self.sets.allocate(&kernel, &bound, &images, sampler).map_err(backend)
        };
        let sets = [set(0)?, set(1)?];
        self.kernels.insert(k, (kernel, sets));
        Ok(())
    }

    fn kernels(&self) -> Vec<KernelRef> {
        self.kernels.keys().copied().collect()
    }

    fn write(&mut self, id: BufferId, bytes: &[u8]) -> Result<(), SolverError> {
        self.staging(bytes.len() as u64)?;
        let dst = self
            .buffers
            .get(id.0 as usize)
            .ok_or_else(|| SolverError::Invalid(format!("no Vulkan buffer {}", id.0)))?;
        upload(&mut self.cmds, &mut self.staging, dst, bytes).map_err(backend)
    }

    fn read(&mut self, id: BufferId) -> Result<Vec<u8>, SolverError> {
        let size = self.buf(id)?.size;
        self.staging(size)?;
        let src = self
            .buffers
            .get(id.0 as usize)
            .ok_or_else(|| SolverError::Invalid(format!("no Vulkan buffer {}", id.0)))?;
        download(&mut self.cmds, &mut self.staging, src, size).map_err(backend)
    }

    fn begin(&mut self, index: usize, queries: u32) -> Result<(), SolverError> {
        self.cmds.begin_at(index, queries).map_err(backend)
    }

    fn record_write(&mut self, id: BufferId, bytes: &[u8]) -> Result<(), SolverError> {
        let len = bytes.len() as u64;
        let not_mapped = || SolverError::Driver("staging not host visible".into());
        if let Ok(at) = self.frame_room(len) {
            let map = self.staging.mapped().ok_or_else(not_mapped)?;
            map[at as usize..at as usize + bytes.len()].copy_from_slice(bytes);
            let dst = self.buf(id)?;
            self.cmds.copy_range(&self.staging, at, dst, 0, len);
            return Ok(());
        }
        // The frame's room is used up: the current chunk, the next one, or a new one.
        let (mut k, mut at) = self.chunk_at;
        at = at.next_multiple_of(STAGING_ALIGN);
        loop {
            if k == self.chunks.len() {
                let usage = vk::BufferUsageFlags::TRANSFER_SRC;
                let size = len.max(FRAME_STAGING);
                let chunk = Buffer::new(&self.dev, "staging chunk", size, usage, MemoryLocation::CpuToGpu);
                self.chunks.push(chunk.map_err(backend)?);
            }
            if at + len <= self.chunks[k].size {
                break;
            }
            (k, at) = (k + 1, 0);
        }
        self.chunk_at = (k, at + len);
        let map = self.chunks[k].mapped().ok_or_else(not_mapped)?;
        map[at as usize..(at + len) as usize].copy_from_slice(bytes);
        let dst = self
            .buffers
            .get(id.0 as usize)
            .ok_or_else(|| SolverError::Invalid(format!("no Vulkan buffer {}", id.0)))?;
        self.cmds.copy_range(&self.chunks[k], at, dst, 0, len);
        Ok(())
    }

    fn clear(&mut self, id: BufferId) {
        if let Some(b) = self.buffers.get(id.0 as usize) {
            self.cmds.zero(b);
        }
    }

    fn copy(&mut self, src: BufferId, dst: BufferId, size: u64) {
        // (A range outside either buffer poisons the recording: refused at submit.)
        if let (Some(a), Some(b)) = (self.buffers.get(src.0 as usize), self.buffers.get(dst.0 as usize)) {
            self.cmds.copy_range(a, 0, b, 0, size);
        }
    }

    fn barrier(&mut self, after_all: bool) {
        if after_all { self.cmds.barrier_after_all() } else { self.cmds.barrier() }
    }

    fn dispatch(&mut self, d: &Dispatch<'_>) {
        let Some((kernel, sets)) = self.kernels.get(&d.kernel) else { return };
        let dsp = raw::Dispatch { kernel, set: &sets[d.parity & 1], push: d.immediates, groups: d.groups };
        self.cmds.dispatch(&dsp, d.timestamps);
    }

    fn readback(&mut self, id: BufferId, size: u64) -> Result<(), SolverError> {
        let size = size.min(self.buf(id)?.size);
        let at = self.frame_room(size)?;
        self.cmds.copy_range(self.buf(id)?, 0, &self.staging, at, size);
        self.readbacks.push((at, size));
        Ok(())
    }

    fn submit(&mut self, last: bool) -> Result<(), SolverError> {
        self.cmds.submit(last).map_err(backend)
    }

    fn wait(&mut self, queries: u32) -> Result<Finished, SolverError> {
        let ticks = self.cmds.wait(queries).map_err(backend)?;
        self.cursor = 0;
        self.chunk_at = (0, 0);
        let map = self.staging.bytes().ok_or_else(|| SolverError::Driver("staging not host visible".into()))?;
        let readbacks =
            self.readbacks.drain(..).map(|(at, size)| map[at as usize..(at + size) as usize].to_vec()).collect();
        Ok(Finished { ticks, readbacks })
    }

    /// The fence of [`Engine::wait`] covers every earlier submission on the queue.
    fn finish(&mut self) -> Result<(), SolverError> {
        Ok(())
    }

    fn check(&mut self, _what: &'static str) -> Result<(), SolverError> {
        let m = self.dev.take_messages();
        if m.is_empty() { Ok(()) } else { Err(backend(VkError::Validation(m.join(" | ")))) }
    }
}

/// The Vulkan solver of `variant` on the first Vulkan device (validated by the Khronos
/// layer with `validation`, where it is installed).
pub fn vulkan_solver(
    variant: impl Into<VariantSpec>,
    scene: clothlab_core::Scene,
    params: clothlab_core::SimParams,
    validation: bool,
    options: SolverOptions,
) -> Result<VulkanSolver, SolverError> {
    GpuSolver::new(VulkanEngine::new(validation)?, variant, scene, params, options)
}

/// Copies `bytes` into `dst` through the staging buffer (which must hold them).
pub(crate) fn upload(cmds: &mut Commands, staging: &mut Buffer, dst: &Buffer, bytes: &[u8]) -> Result<(), VkError> {
    let map = staging
        .mapped()
        .ok_or(VkError::Vulkan { what: "mapping the staging buffer", reason: "not host visible".into() })?;
    map[..bytes.len()].copy_from_slice(bytes);
    cmds.begin(0)?;
    cmds.copy(staging, dst, bytes.len() as u64);
    cmds.submit_and_wait(0).map(|_| ())
}

/// Reads `size` bytes of `src` through the staging buffer (which must hold them).
pub(crate) fn download(cmds: &mut Commands, staging: &mut Buffer, src: &Buffer, size: u64) -> Result<Vec<u8>, VkError> {
    cmds.begin(0)?;
    // The last dispatches' writes become visible to the copy.
    cmds.barrier();
    cmds.copy(src, staging, size);
    cmds.submit_and_wait(0)?;
    let map = staging
        .mapped()
        .ok_or(VkError::Vulkan { what: "mapping the staging buffer", reason: "not host visible".into() })?;
    Ok(map[..size as usize].to_vec())
}
