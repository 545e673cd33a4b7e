//! The API's part of a GPU solver: the [`Engine`] trait. An engine creates buffers,
//! uploads and downloads them, builds kernels, and records dispatches, clears, barriers and
//! timestamps into submissions; everything else a solver does (parameters, grab, state,
//! poisoning, per-kernel timing, statistics, barrier placement) is written once, in
//! [`crate::GpuSolver`], on top of it.
//!
//! Implemented by `clothlab_wgpu::WgpuEngine`, `clothlab_vulkan::VulkanEngine` and
//! `clothlab_gl::GlEngine`. What an API must do differently lives only there: wgpu tracks
//! hazards itself (its [`Engine::barrier`] does nothing) and writes constants through its
//! queue; Vulkan records the frame's constants as a copy in the frame's command buffer,
//! places the barriers it is told to, binds one descriptor set per kernel and parity, and
//! can read the spring table from a sampled image; GL binds buffers to the binding points
//! naga's GLSL names and places `glMemoryBarrier` where it is told to.

use clothlab_core::SolverError;
use clothlab_core::layout::Buf;

use crate::kernels::KernelRef;

/// A buffer an engine created (an index into its own list; valid for that engine only).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct BufferId(pub u32);

/// What an engine's device offers, found when it was opened.
#[derive(Debug, Clone, PartialEq)]
pub struct EngineInfo {
    /// The API, as solver names start: `wgpu`, `vulkan`, `gl`.
    pub api: &'static str,
    /// The adapter, in one line.
    pub adapter: String,
    /// `atomic<f32>` add in storage buffers.
    pub float_atomics: bool,
    /// Immediates (push constants) large enough for the step constants.
    pub immediates: bool,
    /// GPU timestamps between dispatches.
    pub timestamps: bool,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period_ns: f64,
    /// The largest storage binding, bytes.
    pub max_binding: u64,
    /// Subgroup arithmetic in compute shaders (the subgroup statistics).
    pub subgroup_arithmetic: bool,
    /// Relative subgroup shuffles (`subgroupShuffleUp`/`Down`) with the arithmetic: the
    /// `_sh` flavors (`neighbours=shuffle`).
    pub subgroup_shuffle: bool,
    /// The adapter runs on the CPU (lavapipe, llvmpipe, SwiftShader): a few wide threads,
    /// where a kernel's arithmetic, not the lanes it keeps busy, is its cost.
    pub cpu: bool,
    /// The spring table can be read from a sampled image ([`Engine::set_table_image`]).
    pub table_image: bool,
    /// The bodies' distance fields can be read from a filtered 3-D image of 32-bit floats
    /// ([`Engine::set_sdf_image`], `sdf=image`).
    pub sdf_image: bool,
    /// Workgroup (shared) memory a compute shader may declare, bytes (`fusion=tile`).
    pub workgroup_memory: u32,
}

/// One dispatch to record.
#[derive(Debug, Clone, Copy)]
pub struct Dispatch<'a> {
    /// The shader (built before with [`Engine::build`]).
    pub kernel: KernelRef,
    /// Which binding set: the one whose current positions are position buffer `parity`.
    pub parity: usize,
    /// Workgroups in x and y, and the worlds in z (1 for a single run; a batch's
    /// `_w` kernels find their world in `global_invocation_id.z`).
    pub groups: (u32, u32, u32),
    /// Immediates (push constants), maybe empty.
    pub immediates: &'a [u8],
    /// Write timestamps `q` and `q + 1` before and after it.
    pub timestamps: Option<u32>,
}

/// What a finished submission delivers.
#[derive(Debug, Clone, Default)]
pub struct Finished {
    /// The timestamps asked for, in ticks.
    pub ticks: Vec<u64>,
    /// The bytes of every [`Engine::readback`] recorded since the last wait, in order.
    pub readbacks: Vec<Vec<u8>>,
}

/// The API's part of a solver. Every method that can fail returns a [`SolverError`] the
/// user can read; recording methods that cannot fail on the host return nothing (the
/// driver's complaints come back from [`Engine::check`]).
pub trait Engine {
    /// The API's buffer type (what a renderer draws from).
    type Buffer;
    /// What the device offers.
    fn info(&self) -> &EngineInfo;
    /// Creates a buffer bound as `buf` (its kind says uniform or storage) holding
    /// `contents`; with `vertex`, the renderer can draw from it too.
    fn create_buffer(&mut self, buf: Buf, label: &str, contents: &[u8], vertex: bool) -> Result<BufferId, SolverError>;
    /// The buffer `id`.
    fn buffer(&self, id: BufferId) -> &Self::Buffer;
    /// Creates or rewrites the spring-table image ([`Buf::Table`]) from `texels`
    /// (`TABLE_WIDTH` a row, `height` rows).
    fn set_table_image(&mut self, _texels: &[[u32; 4]], _height: u32) -> Result<(), SolverError> {
        Err(SolverError::Unsupported(format!(
            "{}: the spring table as an image is not implemented on {}",
            self.info().adapter,
            self.info().api
        )))
    }
    /// Creates or rewrites the bodies' distance-field image ([`Buf::SdfImage`]): `values`
    /// of `dims` (x fastest, then y, then z) as one `r32float` 3-D image, read through a
    /// trilinear sampler clamped to the edge ([`Buf::SdfSampler`]).
    fn set_sdf_image(&mut self, _values: &[f32], _dims: [u32; 3]) -> Result<(), SolverError> {
        Err(SolverError::Unsupported(format!(
            "{}: the bodies' distance fields as an image are not implemented on {}",
            self.info().adapter,
            self.info().api
        )))
    }
    /// Sets the bindings of the two binding sets (by position parity). Called once, after
    /// the buffers are created and before any kernel is built.
    fn bind(&mut self, sets: [Vec<(Buf, BufferId)>; 2]) -> Result<(), SolverError>;
    /// Builds `kernel`'s pipeline (once) for immediates of `immediates` bytes.
    fn build(&mut self, kernel: KernelRef, immediates: u32) -> Result<(), SolverError>;
    /// The kernels built so far.
    fn kernels(&self) -> Vec<KernelRef>;
    /// Writes `bytes` at the start of buffer `id`, after everything submitted before and
    /// before anything submitted after.
    fn write(&mut self, id: BufferId, bytes: &[u8]) -> Result<(), SolverError>;
    /// The whole of buffer `id`, after everything submitted before.
    fn read(&mut self, id: BufferId) -> Result<Vec<u8>, SolverError>;
    /// Starts recording submission `index` of a frame (0 first), resetting the first
    /// `queries` timestamp queries when not 0.
    fn begin(&mut self, index: usize, queries: u32) -> Result<(), SolverError>;
    /// Records a write of `bytes` at the start of `id`, before the next recorded command.
    fn record_write(&mut self, id: BufferId, bytes: &[u8]) -> Result<(), SolverError>;
    /// Records a fill of `id` with zeros.
    fn clear(&mut self, id: BufferId);
    /// Records a copy of the first `size` bytes of `src` into `dst` (after a barrier).
    fn copy(&mut self, src: BufferId, dst: BufferId, size: u64);
    /// Records a barrier: writes of earlier compute and transfer commands become visible
    /// to later ones; with `after_all`, everything submitted before (the renderer's vertex
    /// reads) completes first.
    fn barrier(&mut self, after_all: bool);
    /// Records a dispatch.
    fn dispatch(&mut self, dispatch: &Dispatch<'_>);
    /// Records a copy of the first `size` bytes of `id` to the host, delivered by the next
    /// [`Engine::wait`].
    fn readback(&mut self, id: BufferId, size: u64) -> Result<(), SolverError>;
    /// Ends and submits the submission being recorded; with `last`, the next
    /// [`Engine::wait`] waits for it (and so for everything before it).
    fn submit(&mut self, last: bool) -> Result<(), SolverError>;
    /// Waits for the last submission where anything must come back (`queries`
    /// timestamps, readbacks), or where the API needs it before recording again.
    fn wait(&mut self, queries: u32) -> Result<Finished, SolverError>;
    /// Blocks until everything submitted is done.
    fn finish(&mut self) -> Result<(), SolverError>;
    /// Fails with what the driver or the validation layer reported since the last call.
    fn check(&mut self, what: &'static str) -> Result<(), SolverError>;
}
