//! The API-overhead micro-benchmarks of `clothlab bench` on raw OpenGL: the calls behind
//! clothlab_core::timing::overhead::OverheadTarget, which repeats, times and checks them
//! the same way as for wgpu and Vulkan. Built as a GL program would build them: GL has no
//! command buffers, so "recording" is issuing the calls (the driver queues them) and
//! "submit and wait" is `glFinish`; `glMemoryBarrier` between two dispatches of the chain;
//! `glQueryCounter` timestamps around it; uploads by `glBufferSubData`, readbacks by
//! `glGetBufferSubData`.

use std::time::Instant;

use clothlab_core::timing::overhead::{ChainSample, OverheadTarget};
use clothlab_core::timing::{OverheadPlan, OverheadRow, elapsed_ns};

use crate::GlError;
use crate::raw::{DispatchDesc, Gl};

/// Elements of the chain's buffer: one workgroup of the `chain` kernel.
const CHAIN_ELEMENTS: usize = 64;

struct Target {
    gl: Gl,
    program: usize,
    data: usize,
    /// The device buffer of the transfer benchmarks.
    transfer: Option<usize>,
}

impl OverheadTarget for Target {
    type Error = GlError;

    fn error(what: &'static str, reason: String) -> GlError {
        GlError::Gl { what, reason }
    }

    fn empty_submit(&mut self) -> Result<(), GlError> {
        self.gl.finish()
    }

    fn chain(&mut self, k: u32) -> Result<ChainSample, GlError> {
        let desc = DispatchDesc {
            program: self.program,
            storage: &[(0, self.data)],
            uniform: &[],
            textures: &[],
            values: &[],
            groups: (1, 1, 1),
        };
        let t = Instant::now();
        self.gl.clear(self.data)?;
        self.gl.timestamp(0)?;
        for j in 0..k {
            if j > 0 {
                self.gl.memory_barrier(glow::SHADER_STORAGE_BARRIER_BIT)?;
            }
            self.gl.dispatch(&desc)?;
        }
        self.gl.timestamp(1)?;
        let record_ns = elapsed_ns(t);
        let t = Instant::now();
        self.gl.finish()?;
        let ticks = self.gl.timestamps(2)?;
        let submit_wait_ns = elapsed_ns(t);
        let gpu_ns = match ticks[..] {
            [t0, t1] => Some(t1.saturating_sub(t0) as f64),
            _ => None,
        };
        Ok(ChainSample { record_ns, submit_wait_ns, gpu_ns })
    }

    fn chain_values(&mut self) -> Result<Vec<u32>, GlError> {
        self.gl.memory_barrier(glow::BUFFER_UPDATE_BARRIER_BIT)?;
        let raw = self.gl.read(self.data, 0, (CHAIN_ELEMENTS * 4) as u64)?;
        Ok(bytemuck::cast_slice(&raw).to_vec())
    }

    fn prepare_transfers(&mut self, bytes: u64) -> Result<(), GlError> {
        self.transfer = Some(self.gl.create_buffer(&vec![0u8; bytes as usize])?);
        Ok(())
    }

    fn upload(&mut self, data: &[u8]) -> Result<(), GlError> {
        let b = self.transfer.ok_or(GlError::Invalid("uploading before the buffers are made"))?;
        self.gl.write(b, 0, data)?;
        self.gl.finish()
    }

    fn readback(&mut self, out: &mut [u8]) -> Result<(), GlError> {
        let b = self.transfer.ok_or(GlError::Invalid("reading back before the buffers are made"))?;
        let bytes = self.gl.read(b, 0, out.len() as u64)?;
        out.copy_from_slice(&bytes);
        Ok(())
    }
}

/// Runs every micro-benchmark of `plan` on a new headless GL context (see
/// clothlab_core::timing::overhead::measure).
pub fn measure(plan: &OverheadPlan) -> Result<Vec<OverheadRow>, GlError> {
    let gl = Gl::headless()?;
    let glsl = clothlab_shaders::kernel("chain").ok_or(GlError::Invalid("no chain kernel"))?.glsl;
    let program = gl.program(glsl, &[]).map_err(|reason| GlError::Gl { what: "building the chain kernel", reason })?;
    let data = gl.create_buffer(&[0u8; CHAIN_ELEMENTS * 4])?;
    let mut target = Target { gl, program, data, transfer: None };
    let rows = clothlab_core::timing::overhead::measure(&mut target, plan)?;
    target.gl.check("running the overhead benchmarks")?;
    Ok(rows)
}
