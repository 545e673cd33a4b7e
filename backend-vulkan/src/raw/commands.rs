//! Recording and submitting compute and transfer work: a ring of command buffers, a
//! fence, timestamps, barriers, copies.

use std::sync::{Arc, Mutex, MutexGuard};

use ash::vk;

use super::{Buffer, Device, Image, Kernel, Set, range, vk_err};
use crate::VkError;

/// A ring of command buffers from one pool, a fence and a timestamp query pool. One
/// buffer is active (being recorded) at a time; a frame may record and submit several
/// (the naive recipe: one per substep) and wait once, on the last.
pub struct Commands {
    pub(super) dev: Arc<Device>,
    pub(super) pool: vk::CommandPool,
    pub(super) cmds: Vec<vk::CommandBuffer>,
    pub(super) active: usize,
    pub(super) fence: vk::Fence,
    pub(super) queries: vk::QueryPool,
    /// Capacity of the query pool.
    pub max_queries: u32,
    pub(super) state: Mutex<State>,
}

/// What the ring knows of its buffers, so that no safe call can misuse them.
#[derive(Debug, Default)]
pub(super) struct State {
    /// Buffers submitted and not waited for.
    pending: Vec<bool>,
    /// A fenced submission is pending.
    fenced: bool,
    /// Objects the device had destroyed when the active recording began.
    epoch: u64,
    /// Why the active recording must not be submitted.
    poisoned: Option<&'static str>,
    /// Timestamp queries written by the active frame (one past the highest).
    queries: u32,
    /// Timestamp queries reset for the active frame.
    reset: u32,
    /// The active buffer is recording.
    recording: bool,
}

/// One recorded dispatch.
pub struct Dispatch<'a> {
    /// The pipeline.
    pub kernel: &'a Kernel,
    /// Its descriptor set.
    pub set: &'a Set,
    /// Push constants (may be empty).
    pub push: &'a [u8],
    /// Workgroups in x, y and z (z: the worlds of a batch).
    pub groups: (u32, u32, u32),
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
                state: Mutex::new(State::default()),
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
        if self.lock().pending.get(index).copied().unwrap_or(false) {
            // Still pending from an earlier frame: wait for it before recording again.
            self.wait(0)?;
        }
        self.active = index;
        {
            let mut st = self.lock();
            st.epoch = self.dev.destroyed();
            st.poisoned = None;
            if index == 0 {
                st.queries = 0;
                st.reset = 0;
            }
            st.reset = st.reset.max(query_count.min(self.max_queries));
            st.recording = true;
        }
        let d = &self.dev.device;
        // SAFETY: the command buffer is not pending (checked above).
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
        {
            let mut st = self.lock();
            if !st.recording || q >= st.reset {
                return;
            }
            st.queries = st.queries.max(q + 1);
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
        if !self.recording() {
            return;
        }
        if !dsp.set.valid() || dsp.set.layout != dsp.kernel.set_layout {
            self.poison("a descriptor set that was dropped or is of another kernel");
            return;
        }
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
                &[dsp.set.set],
                &[],
            );
            if !dsp.push.is_empty() {
                d.cmd_push_constants(self.cmd(), dsp.kernel.layout, vk::ShaderStageFlags::COMPUTE, 0, dsp.push);
            }
            d.cmd_dispatch(self.cmd(), dsp.groups.0, dsp.groups.1, dsp.groups.2);
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
        if !self.recording() {
            return;
        }
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
        let fits = |off: u64, b: &Buffer| off.checked_add(size).is_some_and(|end| end <= b.size);
        if !self.recording() || size == 0 || !fits(src_offset, src) || !fits(dst_offset, dst) {
            self.poison("a copy outside its buffers");
            return;
        }
        let region = [vk::BufferCopy::default().src_offset(src_offset).dst_offset(dst_offset).size(size)];
        // SAFETY: recording state; both buffers are live and the ranges lie within them
        // (checked above).
        unsafe { self.dev.device.cmd_copy_buffer(self.cmd(), src.buffer, dst.buffer, &region) };
    }

    /// Records a copy of `size` bytes from `src` to `dst`.
    pub fn copy(&self, src: &Buffer, dst: &Buffer, size: u64) {
        self.copy_range(src, 0, dst, 0, size);
    }

    /// Records the upload of a whole image from `src` (tightly packed texels): layout to
    /// transfer destination, copy, layout to shader-read-only for compute.
    pub fn copy_to_image(&self, src: &Buffer, dst: &Image) {
        let texels = dst.width as u64 * dst.height as u64 * dst.depth as u64;
        if !self.recording() || src.size < texels * texel_bytes(dst.format) {
            self.poison("an image upload from a buffer too small for it");
            return;
        }
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
            .image_extent(vk::Extent3D { width: dst.width, height: dst.height, depth: dst.depth })];
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
        if !self.recording() {
            return;
        }
        // SAFETY: recording state; the buffer is live and has TRANSFER_DST usage.
        unsafe { self.dev.device.cmd_fill_buffer(self.cmd(), dst.buffer, 0, vk::WHOLE_SIZE, 0) };
    }

    /// Ends the active buffer and submits it; with `fence`, the fence is signalled once it
    /// and every earlier submission on the queue are done (wait with [`Commands::wait`]).
    pub fn submit(&self, fence: bool) -> Result<(), VkError> {
        self.submit_info(fence, &[], &[], &[])
    }

    /// Whether a buffer is being recorded (recording calls do nothing otherwise).
    pub(super) fn recording(&self) -> bool {
        self.lock().recording
    }

    pub(super) fn lock(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Marks the active recording as not to be submitted (a call that would have recorded
    /// something invalid), saying why.
    pub(super) fn poison(&self, why: &'static str) {
        self.lock().poisoned.get_or_insert(why);
    }

    /// Ends the active buffer and submits it with `waits`/`stages`/`signals`, fenced when
    /// asked; refused when the recording was poisoned or an object was destroyed since it
    /// began (it may have recorded that object).
    pub(super) fn submit_info(
        &self,
        fence: bool,
        waits: &[vk::Semaphore],
        stages: &[vk::PipelineStageFlags],
        signals: &[vk::Semaphore],
    ) -> Result<(), VkError> {
        if fence && self.lock().fenced {
            // The fence is in use: wait for it (and all before it) first.
            self.wait(0)?;
        }
        let d = &self.dev.device;
        // SAFETY: the buffer is in recording state (begin_at); ending it has no other
        // precondition.
        if !std::mem::take(&mut self.lock().recording) {
            return Err(VkError::Vulkan { what: "submitting", reason: "nothing is being recorded".into() });
        }
        unsafe { d.end_command_buffer(self.cmd()) }.map_err(vk_err("ending a command buffer"))?;
        let mut st = self.lock();
        let refused =
            st.poisoned
                .or((st.epoch != self.dev.destroyed())
                    .then_some("an object it recorded was dropped before the submission"));
        if let Some(reason) = refused {
            return Err(VkError::Vulkan { what: "submitting", reason: reason.into() });
        }
        let cmds = [self.cmd()];
        let submit = [vk::SubmitInfo::default()
            .command_buffers(&cmds)
            .wait_semaphores(waits)
            .wait_dst_stage_mask(stages)
            .signal_semaphores(signals)];
        let f = if fence { self.fence } else { vk::Fence::null() };
        let _queue = self.dev.queue();
        // SAFETY: the queue lock is held; the buffer is executable and refers only to live
        // objects (nothing was destroyed since it began); the fence is unsignalled and not
        // in use (waited for above); the semaphores are the caller's live objects.
        unsafe { d.queue_submit(self.dev.queue, &submit, f) }.map_err(vk_err("submitting"))?;
        if st.pending.len() <= self.active {
            st.pending.resize(self.active + 1, false);
        }
        st.pending[self.active] = true;
        st.fenced |= fence;
        Ok(())
    }

    /// Waits for the fenced submission (and so for all before it); returns `query_count`
    /// timestamps in ticks.
    pub fn wait(&self, query_count: u32) -> Result<Vec<u64>, VkError> {
        let d = &self.dev.device;
        let mut st = self.lock();
        if st.fenced {
            // SAFETY: a fenced submission is pending, so the fence will be signalled.
            unsafe {
                d.wait_for_fences(&[self.fence], true, u64::MAX).map_err(vk_err("waiting for the GPU"))?;
                d.reset_fences(&[self.fence]).map_err(vk_err("resetting a fence"))?;
            }
        } else if st.pending.iter().any(|p| *p) {
            let _queue = self.dev.queue();
            // SAFETY: the queue lock is held.
            unsafe { d.queue_wait_idle(self.dev.queue) }.map_err(vk_err("waiting for the GPU"))?;
        }
        st.fenced = false;
        st.pending.iter_mut().for_each(|p| *p = false);
        // Only queries this frame wrote (an unwritten one would never become available).
        let written = st.queries;
        drop(st);
        // SAFETY: nothing recorded is pending any more, so the queries can be read.
        unsafe {
            let mut ticks = vec![0u64; query_count.min(written).min(self.max_queries) as usize];
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
        let (queries, fence, pool, cmds) = (self.queries, self.fence, self.pool, std::mem::take(&mut self.cmds));
        // SAFETY: retire runs this once the device is idle (nothing submitted is pending);
        // reverse creation order (null handles, after a failed creation, are ignored).
        self.dev.retire(|d| unsafe {
            d.destroy_query_pool(queries, None);
            d.destroy_fence(fence, None);
            if !cmds.is_empty() {
                d.free_command_buffers(pool, &cmds);
            }
            d.destroy_command_pool(pool, None);
        });
    }
}

/// Bytes per texel of the formats the backend uses.
pub(super) fn texel_bytes(format: vk::Format) -> u64 {
    match format {
        vk::Format::R32G32B32A32_UINT | vk::Format::R32G32B32A32_SFLOAT => 16,
        _ => 4,
    }
}
