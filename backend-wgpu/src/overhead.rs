//! The API-overhead micro-benchmarks of `clothlab bench` on wgpu: an empty submission, a
//! chain of k dependent one-workgroup dispatches, and upload/readback latency. The Vulkan
//! backend has the same four (clothlab_vulkan::overhead), built the way raw Vulkan does
//! them, so the two columns differ only in the API.
//!
//! In wgpu the chain is one compute pass with k dispatches of the `chain` kernel on one
//! read-write storage buffer; wgpu inserts the barrier between each two dispatches itself.

use std::time::Instant;

use clothlab_core::timing::overhead::{
    CHAIN, CPU_RECORD, CPU_SUBMIT_WAIT, CPU_TOTAL, EMPTY_SUBMIT, GPU, READBACK, UPLOAD,
};
use clothlab_core::timing::{OverheadPlan, OverheadRecorder, OverheadRow, elapsed_ns as ns};

use crate::{GpuContext, GpuError};

/// Elements of the chain's buffer: one workgroup of the `chain` kernel.
const CHAIN_ELEMENTS: u64 = 64;

fn fail(what: &'static str, reason: String) -> GpuError {
    GpuError::Wgpu { what, reason }
}

/// Runs every micro-benchmark of `plan` on `ctx`; each result is checked (the chain's
/// buffer holds k, the readback returns what was uploaded) so a benchmark cannot be fast
/// by skipping work.
pub fn measure(ctx: &GpuContext, plan: &OverheadPlan) -> Result<Vec<OverheadRow>, GpuError> {
    let dev = &ctx.device;
    let mut rec = OverheadRecorder::default();
    let reps = plan.warmup + plan.samples;
    let measured = |i: usize| i >= plan.warmup;

    // Empty submission, then wait.
    for i in 0..reps {
        let t = Instant::now();
        let cmd = dev.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("empty") }).finish();
        ctx.queue.submit([cmd]);
        ctx.wait_idle()?;
        if measured(i) {
            rec.record(EMPTY_SUBMIT, 0, CPU_TOTAL, ns(t));
        }
    }

    // Chains of dependent dispatches.
    let kernel = clothlab_shaders::kernel("chain").ok_or_else(|| fail("loading the chain kernel", "missing".into()))?;
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
    use wgpu::BufferUsages as U;
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
    let period = ctx.queue.get_timestamp_period() as f64;
    ctx.check("creating the chain benchmark")?;
    for &k in &plan.chain {
        for i in 0..reps {
            let t = Instant::now();
            let mut enc = dev.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("chain") });
            enc.clear_buffer(&data, 0, None);
            {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("chain"),
                    timestamp_writes: timestamps.as_ref().map(|(set, _)| wgpu::ComputePassTimestampWrites {
                        query_set: set,
                        beginning_of_pass_write_index: Some(0),
                        end_of_pass_write_index: Some(1),
                    }),
                });
                for _ in 0..k {
                    pass.set_pipeline(&pipeline);
                    pass.set_bind_group(0, &bind, &[]);
                    pass.dispatch_workgroups(1, 1, 1);
                }
            }
            if let Some((set, resolve)) = &timestamps {
                enc.resolve_query_set(set, 0..2, resolve, 0);
            }
            let cmd = enc.finish();
            let record = ns(t);
            let t = Instant::now();
            ctx.queue.submit([cmd]);
            ctx.wait_idle()?;
            let submit_wait = ns(t);
            if measured(i) {
                rec.record(CHAIN, k as u64, CPU_RECORD, record);
                rec.record(CHAIN, k as u64, CPU_SUBMIT_WAIT, submit_wait);
                if let Some((_, resolve)) = &timestamps {
                    let raw = ctx.read_buffer(resolve, 0, 16)?;
                    let t: &[u64] = bytemuck::cast_slice(&raw);
                    rec.record(CHAIN, k as u64, GPU, t[1].saturating_sub(t[0]) as f64 * period);
                }
            }
        }
        let raw = ctx.read_buffer(&data, 0, CHAIN_ELEMENTS * 4)?;
        let got: &[u32] = bytemuck::cast_slice(&raw);
        if got.iter().any(|&x| x != k) {
            return Err(fail("checking the chain", format!("after {k} dispatches an element holds {:?}", got[0])));
        }
    }

    // Upload and readback latency.
    for &bytes in &plan.bytes {
        let size = bytes.max(4).next_multiple_of(4);
        let pattern: Vec<u8> = (0..size).map(|i| (i * 7 % 251) as u8).collect();
        let gpu = dev.create_buffer(&wgpu::BufferDescriptor {
            label: Some("latency"),
            size,
            usage: U::STORAGE | U::COPY_DST | U::COPY_SRC,
            mapped_at_creation: false,
        });
        let staging = dev.create_buffer(&wgpu::BufferDescriptor {
            label: Some("latency staging"),
            size,
            usage: U::MAP_READ | U::COPY_DST,
            mapped_at_creation: false,
        });
        let mut out = vec![0u8; size as usize];
        for i in 0..reps {
            let t = Instant::now();
            ctx.queue.write_buffer(&gpu, 0, &pattern);
            ctx.queue.submit([]);
            ctx.wait_idle()?;
            let upload = ns(t);

            let t = Instant::now();
            let mut enc = dev.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("readback") });
            enc.copy_buffer_to_buffer(&gpu, 0, &staging, 0, size);
            ctx.queue.submit([enc.finish()]);
            let slice = staging.slice(..);
            let (tx, rx) = std::sync::mpsc::channel();
            slice.map_async(wgpu::MapMode::Read, move |r| {
                let _ = tx.send(r);
            });
            ctx.wait_idle()?;
            rx.recv().map_err(|e| GpuError::Readback(e.to_string()))?.map_err(|e| GpuError::Readback(e.to_string()))?;
            out.copy_from_slice(&slice.get_mapped_range().map_err(|e| GpuError::Readback(e.to_string()))?);
            staging.unmap();
            let readback = ns(t);
            if measured(i) {
                rec.record(UPLOAD, bytes, CPU_TOTAL, upload);
                rec.record(READBACK, bytes, CPU_TOTAL, readback);
            }
        }
        if out != pattern {
            return Err(fail("checking the readback", format!("{bytes} bytes came back different")));
        }
    }
    ctx.check("the overhead benchmarks")?;
    Ok(rec.rows())
}
