//! The API-overhead micro-benchmarks of `clothlab bench` on wgpu: the calls behind
//! clothlab_core::timing::overhead::OverheadTarget, which repeats, times and checks them
//! the same way as for raw Vulkan (clothlab_vulkan::overhead).
//!
//! The chain is one compute pass with k dispatches of the `chain` kernel on one read-write
//! storage buffer; wgpu inserts the barrier between each two dispatches itself.

use std::time::Instant;

use clothlab_core::timing::overhead::{ChainSample, OverheadTarget};
use clothlab_core::timing::{OverheadPlan, OverheadRow, elapsed_ns};

use crate::{GpuContext, GpuError};

/// Elements of the chain's buffer: one workgroup of the `chain` kernel.
const CHAIN_ELEMENTS: u64 = 64;

use wgpu::BufferUsages as U;

struct Target<'a> {
    ctx: &'a GpuContext,
    pipeline: wgpu::ComputePipeline,
    data: wgpu::Buffer,
    bind: wgpu::BindGroup,
    /// Query set and its resolve buffer, where the adapter has timestamps.
    timestamps: Option<(wgpu::QuerySet, wgpu::Buffer)>,
    /// Device-local buffer and mapped staging buffer of the transfer benchmarks.
    transfer: Option<(wgpu::Buffer, wgpu::Buffer)>,
}

impl Target<'_> {
    fn buffer(&self, label: &str, size: u64, usage: U) -> wgpu::Buffer {
        self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage,
            mapped_at_creation: false,
        })
    }
}

impl OverheadTarget for Target<'_> {
    type Error = GpuError;

    fn error(what: &'static str, reason: String) -> GpuError {
        GpuError::Wgpu { what, reason }
    }

    fn empty_submit(&mut self) -> Result<(), GpuError> {
        let cmd =
            self.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("empty") }).finish();
        self.ctx.queue.submit([cmd]);
        self.ctx.wait_idle()
    }

    fn chain(&mut self, k: u32) -> Result<ChainSample, GpuError> {
        let t = Instant::now();
        let mut enc = self.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("chain") });
        enc.clear_buffer(&self.data, 0, None);
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("chain"),
                timestamp_writes: self.timestamps.as_ref().map(|(set, _)| wgpu::ComputePassTimestampWrites {
                    query_set: set,
                    beginning_of_pass_write_index: Some(0),
                    end_of_pass_write_index: Some(1),
                }),
            });
            for _ in 0..k {
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &self.bind, &[]);
                pass.dispatch_workgroups(1, 1, 1);
            }
        }
        if let Some((set, resolve)) = &self.timestamps {
            enc.resolve_query_set(set, 0..2, resolve, 0);
        }
        let cmd = enc.finish();
        let record_ns = elapsed_ns(t);
        let t = Instant::now();
        self.ctx.queue.submit([cmd]);
        self.ctx.wait_idle()?;
        let submit_wait_ns = elapsed_ns(t);
        // Read after the clock stopped: not part of the chain's cost.
        let gpu_ns = match &self.timestamps {
            Some((_, resolve)) => {
                let raw = self.ctx.read_buffer(resolve, 0, 16)?;
                let ticks: &[u64] = bytemuck::cast_slice(&raw);
                Some(ticks[1].saturating_sub(ticks[0]) as f64 * self.ctx.queue.get_timestamp_period() as f64)
            }
            None => None,
        };
        Ok(ChainSample { record_ns, submit_wait_ns, gpu_ns })
    }

    fn chain_values(&mut self) -> Result<Vec<u32>, GpuError> {
        Ok(bytemuck::cast_slice(&self.ctx.read_buffer(&self.data, 0, CHAIN_ELEMENTS * 4)?).to_vec())
    }

    fn prepare_transfers(&mut self, bytes: u64) -> Result<(), GpuError> {
        let gpu = self.buffer("latency", bytes, U::STORAGE | U::COPY_DST | U::COPY_SRC);
        let staging = self.buffer("latency staging", bytes, U::MAP_READ | U::COPY_DST);
        self.transfer = Some((gpu, staging));
        Ok(())
    }

    fn upload(&mut self, data: &[u8]) -> Result<(), GpuError> {
        let (gpu, _) = self.transfer.as_ref().ok_or_else(|| Self::error("uploading", "no buffer".into()))?;
        self.ctx.queue.write_buffer(gpu, 0, data);
        self.ctx.queue.submit([]);
        self.ctx.wait_idle()
    }

    fn readback(&mut self, out: &mut [u8]) -> Result<(), GpuError> {
        let (gpu, staging) = self.transfer.as_ref().ok_or_else(|| Self::error("reading back", "no buffer".into()))?;
        let mut enc =
            self.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("readback") });
        enc.copy_buffer_to_buffer(gpu, 0, staging, 0, out.len() as u64);
        self.ctx.queue.submit([enc.finish()]);
        let slice = staging.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.ctx.wait_idle()?;
        rx.recv().map_err(|e| GpuError::Readback(e.to_string()))?.map_err(|e| GpuError::Readback(e.to_string()))?;
        out.copy_from_slice(&slice.get_mapped_range().map_err(|e| GpuError::Readback(e.to_string()))?);
        staging.unmap();
        Ok(())
    }
}

/// Runs every micro-benchmark of `plan` on `ctx` (see clothlab_core::timing::overhead::measure).
pub fn measure(ctx: &GpuContext, plan: &OverheadPlan) -> Result<Vec<OverheadRow>, GpuError> {
    let dev = &ctx.device;
    let kernel = clothlab_shaders::kernel("chain")
        .ok_or_else(|| GpuError::Wgpu { what: "loading the chain kernel", reason: "missing".into() })?;
    let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("chain"),
        source: wgpu::ShaderSource::Wgsl(kernel.wgsl.into()),
    });
    let pipeline = dev.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("chain"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let data = dev.create_buffer(&wgpu::BufferDescriptor {
        label: Some("chain data"),
        size: CHAIN_ELEMENTS * 4,
        usage: U::STORAGE | U::COPY_DST | U::COPY_SRC,
        mapped_at_creation: false,
    });
    let bind = dev.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("chain"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry { binding: 0, resource: data.as_entire_binding() }],
    });
    let timestamps = ctx.timestamps.then(|| {
        let set = dev.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("chain timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: 2,
        });
        let resolve = dev.create_buffer(&wgpu::BufferDescriptor {
            label: Some("chain resolve"),
            size: 16,
            usage: U::QUERY_RESOLVE | U::COPY_SRC,
            mapped_at_creation: false,
        });
        (set, resolve)
    });
    ctx.check("creating the overhead benchmarks")?;
    let mut target = Target { ctx, pipeline, data, bind, timestamps, transfer: None };
    let rows = clothlab_core::timing::overhead::measure(&mut target, plan)?;
    ctx.check("the overhead benchmarks")?;
    Ok(rows)
}
