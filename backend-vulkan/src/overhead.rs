//! The API-overhead micro-benchmarks of `clothlab bench` on raw Vulkan: the calls behind
//! clothlab_core::timing::overhead::OverheadTarget, which repeats, times and checks them
//! the same way as for wgpu (clothlab_wgpu::overhead). Built as a Vulkan program would
//! build them: one pre-allocated command buffer re-recorded per sample, a global memory
//! barrier between two dispatches of the chain, a fence wait, timestamps around the chain.

use std::sync::Arc;
use std::time::Instant;

use ash::vk;
use clothlab_core::timing::overhead::{ChainSample, OverheadTarget};
use clothlab_core::timing::{OverheadPlan, OverheadRow, elapsed_ns};
use gpu_allocator::MemoryLocation;

use crate::VkError;
use crate::raw::{Buffer, Commands, Device, Dispatch, Kernel, Set, Sets};
use crate::solver::{download, upload};

/// Elements of the chain's buffer: one workgroup of the `chain` kernel.
const CHAIN_ELEMENTS: u64 = 64;

const USAGE: vk::BufferUsageFlags = vk::BufferUsageFlags::from_raw(
    vk::BufferUsageFlags::STORAGE_BUFFER.as_raw()
        | vk::BufferUsageFlags::TRANSFER_SRC.as_raw()
        | vk::BufferUsageFlags::TRANSFER_DST.as_raw(),
);

struct Target {
    dev: Arc<Device>,
    cmds: Commands,
    kernel: Kernel,
    set: Set,
    data: Buffer,
    /// Host-visible copy of the chain buffer for the check.
    check: Buffer,
    /// Device-local buffer, upload staging, readback staging of the transfer benchmarks.
    transfer: Option<(Buffer, Buffer, Buffer)>,
}

impl OverheadTarget for Target {
    type Error = VkError;

    fn error(what: &'static str, reason: String) -> VkError {
        VkError::Vulkan { what, reason }
    }

    fn empty_submit(&mut self) -> Result<(), VkError> {
        self.cmds.begin(0)?;
        self.cmds.submit_and_wait(0).map(|_| ())
    }

    fn chain(&mut self, k: u32) -> Result<ChainSample, VkError> {
        let queries = if self.dev.timestamps { 2 } else { 0 };
        let dispatch = Dispatch { kernel: &self.kernel, set: &self.set, push: &[], groups: (1, 1, 1) };
        let t = Instant::now();
        self.cmds.begin(queries)?;
        self.cmds.zero(&self.data);
        self.cmds.barrier();
        if queries > 0 {
            self.cmds.timestamp(0);
        }
        for j in 0..k {
            if j > 0 {
                self.cmds.barrier();
            }
            self.cmds.dispatch(&dispatch, None);
        }
        if queries > 0 {
            self.cmds.timestamp(1);
        }
        let record_ns = elapsed_ns(t);
        let t = Instant::now();
        let ticks = self.cmds.submit_and_wait(queries)?;
        let submit_wait_ns = elapsed_ns(t);
        let gpu_ns = match ticks[..] {
            [t0, t1] => Some(t1.saturating_sub(t0) as f64 * self.dev.timestamp_period as f64),
            _ => None,
        };
        Ok(ChainSample { record_ns, submit_wait_ns, gpu_ns })
    }

    fn chain_values(&mut self) -> Result<Vec<u32>, VkError> {
        let raw = download(&mut self.cmds, &mut self.check, &self.data, CHAIN_ELEMENTS * 4)?;
        Ok(bytemuck::cast_slice(&raw).to_vec())
    }

    fn prepare_transfers(&mut self, bytes: u64) -> Result<(), VkError> {
        self.transfer = Some((
            Buffer::new(&self.dev, "latency", bytes, USAGE, MemoryLocation::GpuOnly)?,
            Buffer::new(&self.dev, "latency upload", bytes, USAGE, MemoryLocation::CpuToGpu)?,
            Buffer::new(&self.dev, "latency readback", bytes, USAGE, MemoryLocation::GpuToCpu)?,
        ));
        Ok(())
    }

    fn upload(&mut self, data: &[u8]) -> Result<(), VkError> {
        let (gpu, up, _) = self.transfer.as_mut().ok_or_else(|| Self::error("uploading", "no buffer".into()))?;
        upload(&mut self.cmds, up, gpu, data)
    }

    fn readback(&mut self, out: &mut [u8]) -> Result<(), VkError> {
        let (gpu, _, down) = self.transfer.as_ref().ok_or_else(|| Self::error("reading back", "no buffer".into()))?;
        // As download() does, but into `out` (allocated once, as on wgpu), not a new Vec.
        self.cmds.begin(0)?;
        self.cmds.barrier();
        self.cmds.copy(gpu, down, out.len() as u64);
        self.cmds.submit_and_wait(0)?;
        let bytes = down.bytes().ok_or_else(|| Self::error("mapping the readback buffer", "not mapped".into()))?;
        out.copy_from_slice(&bytes[..out.len()]);
        Ok(())
    }
}

/// Runs every micro-benchmark of `plan` on `dev` (see clothlab_core::timing::overhead::measure).
pub fn measure(dev: &crate::Device, plan: &OverheadPlan) -> Result<Vec<OverheadRow>, VkError> {
    let dev = dev.raw();
    let spirv = clothlab_shaders::kernel("chain")
        .ok_or_else(|| VkError::Vulkan { what: "loading the chain kernel", reason: "missing".into() })?
        .spirv;
    let kernel = Kernel::new(dev, spirv, &[(0, vk::DescriptorType::STORAGE_BUFFER)], 0)?;
    let data = Buffer::new(dev, "chain data", CHAIN_ELEMENTS * 4, USAGE, MemoryLocation::GpuOnly)?;
    let sets = Sets::new(dev, 1)?;
    let set = sets.allocate(&kernel, &[(0, vk::DescriptorType::STORAGE_BUFFER, &data)], &[], None)?;
    let check = Buffer::new(dev, "chain check", CHAIN_ELEMENTS * 4, USAGE, MemoryLocation::GpuToCpu)?;
    let mut target =
        Target { dev: dev.clone(), cmds: Commands::new(dev, 2)?, kernel, set, data, check, transfer: None };
    let rows = clothlab_core::timing::overhead::measure(&mut target, plan)?;
    let messages = dev.take_messages();
    if !messages.is_empty() {
        return Err(VkError::Validation(messages.join("; ")));
    }
    Ok(rows)
}
