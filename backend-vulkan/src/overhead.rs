//! The API-overhead micro-benchmarks of `clothlab bench` on raw Vulkan: the same four as
//! clothlab_wgpu::overhead (empty submission, chain of k dependent one-workgroup
//! dispatches, upload and readback latency), built as a Vulkan program would build them:
//! one pre-allocated command buffer re-recorded per sample, a global memory barrier
//! between two dispatches of the chain, a fence wait, timestamps around the chain.

use std::sync::Arc;
use std::time::Instant;

use ash::vk;
use clothlab_core::timing::overhead::{
    CHAIN, CPU_RECORD, CPU_SUBMIT_WAIT, CPU_TOTAL, EMPTY_SUBMIT, GPU, READBACK, UPLOAD,
};
use clothlab_core::timing::{OverheadPlan, OverheadRecorder, OverheadRow, elapsed_ns as ns};
use gpu_allocator::MemoryLocation;

use crate::VkError;
use crate::raw::{Buffer, Commands, Device, Dispatch, Kernel, Sets};
use crate::solver::{download, upload};

/// Elements of the chain's buffer: one workgroup of the `chain` kernel.
const CHAIN_ELEMENTS: u64 = 64;

fn fail(what: &'static str, reason: String) -> VkError {
    VkError::Vulkan { what, reason }
}

/// Runs every micro-benchmark of `plan` on `dev`; each result is checked (the chain's
/// buffer holds k, the readback returns what was uploaded).
pub fn measure(dev: &Arc<Device>, plan: &OverheadPlan) -> Result<Vec<OverheadRow>, VkError> {
    let mut rec = OverheadRecorder::default();
    let reps = plan.warmup + plan.samples;
    let measured = |i: usize| i >= plan.warmup;
    let mut cmds = Commands::new(dev, 2)?;

    // Empty submission, then wait.
    for i in 0..reps {
        let t = Instant::now();
        cmds.begin(0)?;
        cmds.submit_and_wait(0)?;
        if measured(i) {
            rec.record(EMPTY_SUBMIT, 0, CPU_TOTAL, ns(t));
        }
    }

    // Chains of dependent dispatches.
    let usage =
        vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
    let kernel = clothlab_shaders::kernel("chain").ok_or_else(|| fail("loading the chain kernel", "missing".into()))?;
    let pipeline = Kernel::new(dev, kernel.spirv, &[(0, vk::DescriptorType::STORAGE_BUFFER)], 0)?;
    let data = Buffer::new(dev, "chain data", CHAIN_ELEMENTS * 4, usage, MemoryLocation::GpuOnly)?;
    let sets = Sets::new(dev, 1)?;
    let set = sets.allocate(&pipeline, &[(0, vk::DescriptorType::STORAGE_BUFFER, &data)], None)?;
    let mut check = Buffer::new(dev, "chain check", CHAIN_ELEMENTS * 4, usage, MemoryLocation::GpuToCpu)?;
    let dispatch = Dispatch { kernel: &pipeline, set, push: &[], groups: (1, 1) };
    let timed = dev.timestamps;
    for &k in &plan.chain {
        for i in 0..reps {
            let t = Instant::now();
            cmds.begin(if timed { 2 } else { 0 })?;
            cmds.zero(&data);
            cmds.barrier();
            if timed {
                cmds.timestamp(0);
            }
            for j in 0..k {
                if j > 0 {
                    cmds.barrier();
                }
                cmds.dispatch(&dispatch, None);
            }
            if timed {
                cmds.timestamp(1);
            }
            let record = ns(t);
            let t = Instant::now();
            let ticks = cmds.submit_and_wait(if timed { 2 } else { 0 })?;
            let submit_wait = ns(t);
            if measured(i) {
                rec.record(CHAIN, k as u64, CPU_RECORD, record);
                rec.record(CHAIN, k as u64, CPU_SUBMIT_WAIT, submit_wait);
                if let [t0, t1] = ticks[..] {
                    rec.record(CHAIN, k as u64, GPU, t1.saturating_sub(t0) as f64 * dev.timestamp_period as f64);
                }
            }
        }
        let raw = download(&mut cmds, &mut check, &data, CHAIN_ELEMENTS * 4)?;
        let got: &[u32] = bytemuck::cast_slice(&raw);
        if got.iter().any(|&x| x != k) {
            return Err(fail("checking the chain", format!("after {k} dispatches an element holds {}", got[0])));
        }
    }

    // Upload and readback latency.
    for &bytes in &plan.bytes {
        let size = bytes.max(4).next_multiple_of(4);
        let pattern: Vec<u8> = (0..size).map(|i| (i * 7 % 251) as u8).collect();
        let gpu = Buffer::new(dev, "latency", size, usage, MemoryLocation::GpuOnly)?;
        let mut up = Buffer::new(dev, "latency upload", size, usage, MemoryLocation::CpuToGpu)?;
        let down = Buffer::new(dev, "latency readback", size, usage, MemoryLocation::GpuToCpu)?;
        let mut out = vec![0u8; size as usize];
        for i in 0..reps {
            let t = Instant::now();
            upload(&mut cmds, &mut up, &gpu, &pattern)?;
            let upload_ns = ns(t);
            // As download() does, into a buffer allocated once (as the wgpu twin does).
            let t = Instant::now();
            cmds.begin(0)?;
            cmds.barrier();
            cmds.copy(&gpu, &down, size);
            cmds.submit_and_wait(0)?;
            out.copy_from_slice(down.bytes().ok_or_else(|| fail("mapping the readback buffer", "not mapped".into()))?);
            let readback_ns = ns(t);
            if measured(i) {
                rec.record(UPLOAD, bytes, CPU_TOTAL, upload_ns);
                rec.record(READBACK, bytes, CPU_TOTAL, readback_ns);
            }
        }
        if out != pattern {
            return Err(fail("checking the readback", format!("{bytes} bytes came back different")));
        }
    }
    let messages = dev.take_messages();
    if !messages.is_empty() {
        return Err(VkError::Validation(messages.join("; ")));
    }
    Ok(rec.rows())
}
