//! The wgpu solver: buffers, pipelines, and the recipe of dispatches per substep.

use std::collections::HashMap;
use std::time::Instant;

use clothlab_core::grid::{
    ClothState, ClothTopology, Grab, InteriorSlots, STRAIN_SLOTS, SpringSlot, StepParams, V4, build, spring_constants,
};
use clothlab_core::layout::Buf;
use clothlab_core::scene::{Aabb, MAX_COLLIDERS, Scene, Sphere};
use clothlab_core::solver::{Solver, SolverError};
use clothlab_core::timing::{CPU_RECORD, CPU_SUBMIT, FRAME, KernelTimings, TimingRecorder};
use clothlab_core::{SimParams, cpu};
use clothlab_engine::kernels::{self, HostBuffers, KernelRef, groups};
use clothlab_engine::recipe::{Caps, Command, Variant, kernels_for, kernels_of, recipe};
use clothlab_engine::tables::{record_times, split_slots, spring_halves};
use clothlab_engine::validate::KernelRunner;
use wgpu::util::DeviceExt;

use crate::context::{GpuContext, GpuError};

const V4_SIZE: u64 = 16;
/// Most timestamp queries per submission.
const MAX_QUERIES: u32 = 4096;

struct Buffers {
    params: wgpu::Buffer,
    /// The position pair; `cur` says which holds the positions.
    pos: [wgpu::Buffer; 2],
    prev: wgpu::Buffer,
    force: wgpu::Buffer,
    normal: wgpu::Buffer,
    faces: wgpu::Buffer,
    spheres: wgpu::Buffer,
    boxes: wgpu::Buffer,
    /// Slots 0..8 of every particle (structural, shear).
    slots: wgpu::Buffer,
    /// Slots 8..12 of every particle (bend).
    bend_slots: wgpu::Buffer,
    /// The interior's shared spring constants (uniform).
    interior: wgpu::Buffer,
    /// The flat spring list, first half.
    springs: wgpu::Buffer,
    /// The flat spring list, second half.
    springs_b: wgpu::Buffer,
    tethers: wgpu::Buffer,
    triangles: wgpu::Buffer,
    face_slots: wgpu::Buffer,
}

fn entry(binding: u32, buf: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry { binding, resource: buf.as_entire_binding() }
}

struct Timestamps {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    period_ns: f64,
}

/// The cloth solver on wgpu.
pub struct WgpuSolver {
    ctx: GpuContext,
    variant: Variant,
    scene: Scene,
    params: SimParams,
    grab: Option<Grab>,
    topo: ClothTopology,
    buffers: Buffers,
    bind_groups: [wgpu::BindGroup; 2],
    pipelines: HashMap<KernelRef, wgpu::ComputePipeline>,
    plain_layout: wgpu::PipelineLayout,
    imm_layout: Option<wgpu::PipelineLayout>,
    recipe: Vec<Command>,
    /// Which of `buffers.pos` holds the current positions.
    cur: usize,
    /// The step constants of the frame being recorded (for kernels reading immediates).
    sp: StepParams,
    caps: Caps,
    timestamps: Option<Timestamps>,
    timer: TimingRecorder,
    /// Record per-kernel GPU timings (reads timestamps back after every submission).
    pub time_kernels: bool,
}

fn buffer_entry(binding: u32, ty: wgpu::BufferBindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    }
}

fn storage(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    buffer_entry(binding, wgpu::BufferBindingType::Storage { read_only })
}

fn uniform(binding: u32) -> wgpu::BindGroupLayoutEntry {
    buffer_entry(binding, wgpu::BufferBindingType::Uniform)
}

impl WgpuSolver {
    /// Builds the cloth of `scene` on the first adapter found.
    pub fn new(variant: Variant, scene: Scene, params: SimParams) -> Result<Self, SolverError> {
        let ctx = GpuContext::new().map_err(backend)?;
        Self::with_context(ctx, variant, scene, params)
    }

    /// Builds the cloth of `scene` on `ctx`.
    pub fn with_context(
        ctx: GpuContext,
        variant: Variant,
        scene: Scene,
        params: SimParams,
    ) -> Result<Self, SolverError> {
        if scene.spheres.len() > MAX_COLLIDERS || scene.boxes.len() > MAX_COLLIDERS {
            return Err(SolverError::Invalid(format!("at most {MAX_COLLIDERS} spheres and boxes")));
        }
        // Refuse a grid whose buffers the adapter cannot bind, naming the size it can take.
        let limits = ctx.device.limits();
        let max_binding = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        // The largest buffer is the structural and shear half of the spring table.
        let per_particle = (STRAIN_SLOTS * std::mem::size_of::<SpringSlot>()) as u64;
        SolverError::check_table(scene.cloth.n, per_particle, max_binding, &ctx.info.name)?;
        let (mut state, topo) = build(&scene, &params)?;
        // Initial normals and wind, as the CPU solvers start.
        let sp = StepParams::new(&params, &scene, None);
        let mut face = vec![[0.0f32; 4]; topo.triangles.len()];
        cpu::tri_normals(cpu::Exec::Serial, &topo.triangles, &state.pos, &mut face);
        cpu::vertex_normals(cpu::Exec::Serial, &sp, &topo.face_slots, &face, &mut state.normal, &mut state.force);

        let dev = &ctx.device;
        let init = |label: &str, contents: &[u8], usage: wgpu::BufferUsages| {
            dev.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
        };
        use wgpu::BufferUsages as U;
        let state_usage = U::STORAGE | U::VERTEX | U::COPY_SRC | U::COPY_DST;
        let data_usage = U::STORAGE | U::COPY_DST;
        let mut spheres = [Sphere { center: [0.0; 3], radius: 0.0 }; MAX_COLLIDERS];
        spheres[..scene.spheres.len()].copy_from_slice(&scene.spheres);
        let mut boxes = [Aabb::new([0.0; 3], [0.0; 3]); MAX_COLLIDERS];
        boxes[..scene.boxes.len()].copy_from_slice(&scene.boxes);
        let tri_flat: Vec<u32> = topo.triangles.iter().flatten().copied().collect();
        let face_flat: Vec<i32> = topo.face_slots.iter().flatten().copied().collect();
        let (strain_slots, bend_slots) = split_slots(&topo);
        let buffers = Buffers {
            params: init("params", bytemuck::bytes_of(&sp), U::UNIFORM | U::COPY_DST),
            pos: [
                init("pos0", bytemuck::cast_slice(&state.pos), state_usage),
                init("pos1", bytemuck::cast_slice(&state.pos), state_usage),
            ],
            prev: init("prev", bytemuck::cast_slice(&state.prev), state_usage),
            force: init("force", bytemuck::cast_slice(&state.force), state_usage),
            normal: init("normal", bytemuck::cast_slice(&state.normal), state_usage),
            faces: init("faces", bytemuck::cast_slice(&face), U::STORAGE | U::COPY_SRC | U::COPY_DST),
            spheres: init("spheres", bytemuck::cast_slice(&spheres), data_usage),
            boxes: init("boxes", bytemuck::cast_slice(&boxes), data_usage),
            interior: init("interior slots", bytemuck::bytes_of(&InteriorSlots::new(&topo)), U::UNIFORM | U::COPY_DST),
            slots: init("slots", bytemuck::cast_slice(&strain_slots), data_usage),
            bend_slots: init("bend slots", bytemuck::cast_slice(&bend_slots), data_usage),
            springs: init("springs", bytemuck::cast_slice(spring_halves(&topo.springs).0), data_usage),
            springs_b: init("springs (2nd half)", bytemuck::cast_slice(spring_halves(&topo.springs).1), data_usage),
            tethers: init("tethers", bytemuck::cast_slice(&topo.tethers), data_usage),
            triangles: init("triangles", bytemuck::cast_slice(&tri_flat), data_usage | U::INDEX),
            face_slots: init("face_slots", bytemuck::cast_slice(&face_flat), data_usage),
        };

        let layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("cloth"),
            entries: &[
                uniform(0),
                storage(1, false),
                storage(2, false),
                storage(3, false),
                storage(4, false),
                storage(5, false),
                storage(6, true),
                storage(7, true),
                storage(8, true),
                storage(9, true),
                storage(10, true),
                storage(11, false),
                storage(12, true),
                storage(13, true),
                storage(14, true),
                storage(15, true),
                uniform(16),
            ],
        });
        let bind = |k: usize| {
            let b = &buffers;
            let e = entry;
            dev.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(if k == 0 { "cloth (pos0)" } else { "cloth (pos1)" }),
                layout: &layout,
                entries: &[
                    e(0, &b.params),
                    e(1, &b.pos[k]),
                    e(2, &b.prev),
                    e(3, &b.force),
                    e(4, &b.normal),
                    e(5, &b.pos[1 - k]),
                    e(6, &b.slots),
                    e(7, &b.springs),
                    e(8, &b.tethers),
                    e(9, &b.triangles),
                    e(10, &b.face_slots),
                    e(11, &b.faces),
                    e(12, &b.spheres),
                    e(13, &b.boxes),
                    e(14, &b.bend_slots),
                    e(15, &b.springs_b),
                    e(16, &b.interior),
                ],
            })
        };
        let bind_groups = [bind(0), bind(1)];
        let caps = Caps { float_atomics: ctx.float_atomics, immediates: ctx.immediates, table_image: false };
        let pipeline_layout = |immediate_size: u32| {
            dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("cloth"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size,
            })
        };
        let plain_layout = pipeline_layout(0);
        let imm_layout = caps.immediates.then(|| pipeline_layout(std::mem::size_of::<StepParams>() as u32));
        let timestamps = ctx.timestamps.then(|| Timestamps {
            set: dev.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("kernel timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: MAX_QUERIES,
            }),
            resolve: dev.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp resolve"),
                size: MAX_QUERIES as u64 * 8,
                usage: U::QUERY_RESOLVE | U::COPY_SRC,
                mapped_at_creation: false,
            }),
            period_ns: ctx.queue.get_timestamp_period() as f64,
        });
        let recipe = recipe(variant, params.strain_iterations, caps);
        let mut solver = Self {
            ctx,
            variant,
            scene,
            params,
            grab: None,
            topo,
            buffers,
            bind_groups,
            pipelines: HashMap::new(),
            plain_layout,
            imm_layout,
            recipe,
            cur: 0,
            sp,
            caps,
            timestamps,
            timer: TimingRecorder::default(),
            time_kernels: true,
        };
        for k in kernels_for(caps) {
            solver.build(k)?;
        }
        solver.ctx.check("creating the solver").map_err(backend)?;
        Ok(solver)
    }

    /// Builds the pipeline of `k` (once).
    fn build(&mut self, k: KernelRef) -> Result<(), SolverError> {
        if self.pipelines.contains_key(&k) {
            return Ok(());
        }
        let name = k.shader_name();
        let wgsl = k.wgsl()?;
        if !matches!(k.def.source, kernels::Source::Builtin) {
            // naga's message, with the line, before wgpu sees it.
            clothlab_shaders::compile_spirv(&name, &wgsl)
                .map_err(|reason| SolverError::Shader { kernel: name.clone(), reason })?;
        }
        let dev = &self.ctx.device;
        let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(&name),
            source: wgpu::ShaderSource::Wgsl(wgsl),
        });
        let layout = match (&self.imm_layout, k.step_immediates()) {
            (Some(l), true) => l,
            (None, true) => {
                return Err(SolverError::Shader { kernel: name, reason: "this adapter has no immediates".into() });
            }
            _ => &self.plain_layout,
        };
        let pipeline = dev.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(&name),
            layout: Some(layout),
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
        self.pipelines.insert(k, pipeline);
        Ok(())
    }

    fn buffer(&self, buf: Buf) -> Option<&wgpu::Buffer> {
        let b = &self.buffers;
        Some(match buf {
            Buf::Pos => &b.pos[self.cur],
            Buf::PosOut => &b.pos[1 - self.cur],
            Buf::Prev => &b.prev,
            Buf::Force => &b.force,
            Buf::Normal => &b.normal,
            Buf::Faces => &b.faces,
            Buf::Params => &b.params,
            _ => return None,
        })
    }

    /// The adapter in use, in one line.
    pub fn adapter(&self) -> String {
        self.ctx.describe()
    }

    /// The kernels one substep dispatches, in order (strain passes once).
    pub fn recipe_kernels(&self) -> Vec<KernelRef> {
        kernels_of(&self.recipe)
    }

    /// The commands of one substep.
    pub fn commands(&self) -> &[Command] {
        &self.recipe
    }

    /// Whether the optimized kernels read the step constants from immediates.
    pub fn immediates(&self) -> bool {
        self.caps.immediates
    }

    /// Whether the naive scatters use float atomics (else compare-exchange loops).
    pub fn float_atomics(&self) -> bool {
        self.ctx.float_atomics
    }

    /// The GPU context.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// The buffer holding the current positions (`VERTEX | STORAGE`), and the normals'.
    pub fn vertex_buffers(&self) -> (&wgpu::Buffer, &wgpu::Buffer) {
        (&self.buffers.pos[self.cur], &self.buffers.normal)
    }

    /// Records `commands` into `enc`, writing timestamps from query `*q` on while there
    /// is room. Returns the labels of the timed dispatches in order.
    fn record(
        &mut self,
        enc: &mut wgpu::CommandEncoder,
        commands: &[Command],
        q: &mut u32,
        labels: &mut Vec<&'static str>,
    ) {
        for c in commands {
            let k = match c {
                Command::Clear(buf) => {
                    if let Some(b) = self.buffer(*buf) {
                        enc.clear_buffer(b, 0, None);
                    }
                    continue;
                }
                Command::Swap => {
                    self.cur ^= 1;
                    continue;
                }
                Command::Dispatch(k) => *k,
            };
            let timed = self.time_kernels && self.timestamps.is_some() && *q + 2 <= MAX_QUERIES;
            let timestamp_writes = match (&self.timestamps, timed) {
                (Some(ts), true) => Some(wgpu::ComputePassTimestampWrites {
                    query_set: &ts.set,
                    beginning_of_pass_write_index: Some(*q),
                    end_of_pass_write_index: Some(*q + 1),
                }),
                _ => None,
            };
            let mut pass =
                enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(k.def.label), timestamp_writes });
            pass.set_pipeline(&self.pipelines[&k]);
            if k.step_immediates() {
                pass.set_immediates(0, bytemuck::bytes_of(&self.sp));
            }
            pass.set_bind_group(0, &self.bind_groups[self.cur], &[]);
            let (x, y) = groups(k.def.count.of(&self.topo));
            pass.dispatch_workgroups(x, y, 1);
            drop(pass);
            if timed {
                *q += 2;
                labels.push(k.def.label);
            }
        }
    }

    /// Resolves the `q` timestamps of the frame just submitted, reads them back once, and
    /// records the per-dispatch times; returns the frame's GPU span (first dispatch begin to
    /// last end, so for the naive variant the gaps between its submissions count too).
    fn read_times(&mut self, q: u32, labels: &[&'static str]) -> Result<Option<f64>, SolverError> {
        let Some(ts) = self.timestamps.as_ref().filter(|_| q > 0) else {
            return Ok(None);
        };
        let mut enc =
            self.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("timestamps") });
        enc.resolve_query_set(&ts.set, 0..q, &ts.resolve, 0);
        self.ctx.queue.submit([enc.finish()]);
        let raw = self.ctx.read_buffer(&ts.resolve, 0, q as u64 * 8).map_err(backend)?;
        let ticks: &[u64] = bytemuck::cast_slice(&raw);
        Ok(Some(record_times(
            &mut self.timer,
            labels,
            ticks,
            ts.period_ns,
            clothlab_engine::cpu::dispatch_count(&self.recipe),
        )))
    }

    /// Uploads `bufs` and `sp`, runs `commands`, reads the buffers back (see
    /// [`KernelRunner::run_commands`]). The next frame uploads the solver's own constants.
    fn run_host(&mut self, commands: &[Command], sp: &StepParams, bufs: &mut HostBuffers) -> Result<(), SolverError> {
        bufs.check(&self.topo, sp)?;
        for k in clothlab_engine::recipe::dispatches(commands) {
            self.build(k)?;
        }
        self.sp = *sp;
        let q = &self.ctx.queue;
        q.write_buffer(&self.buffers.params, 0, bytemuck::bytes_of(sp));
        for buf in [Buf::Pos, Buf::PosOut, Buf::Prev, Buf::Force, Buf::Normal, Buf::Faces] {
            let (Some(dst), Some(src)) = (self.buffer(buf), bufs.get(buf)) else { continue };
            q.write_buffer(dst, 0, bytemuck::cast_slice(src));
        }
        let mut enc =
            self.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("commands") });
        let was = self.time_kernels;
        self.time_kernels = false;
        self.record(&mut enc, commands, &mut 0, &mut Vec::new());
        self.time_kernels = was;
        self.ctx.queue.submit([enc.finish()]);
        self.ctx.check("running commands").map_err(backend)?;
        for buf in [Buf::Pos, Buf::PosOut, Buf::Prev, Buf::Force, Buf::Normal, Buf::Faces] {
            let Some(src) = self.buffer(buf) else { continue };
            let raw = self.ctx.read_buffer(src, 0, src.size()).map_err(backend)?;
            if let Some(dst) = bufs.get_mut(buf) {
                *dst = bytemuck::cast_slice::<u8, V4>(&raw).to_vec();
            }
        }
        Ok(())
    }
}

impl KernelRunner for WgpuSolver {
    fn kernels(&self) -> Vec<KernelRef> {
        let mut v: Vec<KernelRef> = self.pipelines.keys().copied().collect();
        v.sort_by_key(|k| k.shader_name());
        v
    }

    fn run_commands(
        &mut self,
        commands: &[Command],
        p: &StepParams,
        bufs: &mut HostBuffers,
    ) -> Result<(), SolverError> {
        self.run_host(commands, p, bufs)
    }

    fn adapter(&self) -> String {
        self.ctx.describe()
    }

    fn add_kernel(&mut self, kernel: KernelRef) -> Result<(), SolverError> {
        self.build(kernel)?;
        self.ctx.check("building a kernel").map_err(backend)
    }
}

fn backend(e: GpuError) -> SolverError {
    match e {
        GpuError::NoAdapter => SolverError::NoAdapter(e.to_string()),
        e => SolverError::Driver(e.to_string()),
    }
}

impl Solver for WgpuSolver {
    fn name(&self) -> &str {
        match self.variant {
            Variant::Naive => "wgpu-naive",
            Variant::Optimized => "wgpu",
        }
    }

    fn scene(&self) -> &Scene {
        &self.scene
    }

    fn params(&self) -> &SimParams {
        &self.params
    }

    fn set_params(&mut self, params: SimParams) -> Result<(), SolverError> {
        params.validate()?;
        let n = self.topo.n;
        if spring_constants(&params, n) == spring_constants(&self.params, n) {
            // Wind, gravity and the like reach the kernels with the next frame's constants.
            self.recipe = recipe(self.variant, params.strain_iterations, self.caps);
            self.params = params;
            return Ok(());
        }
        self.topo.set_spring_constants(&params);
        // The spring constants depend on dt and the stiffness fractions: rewrite both tables
        // in place (the bind groups keep pointing at the same buffers).
        let q = &self.ctx.queue;
        q.write_buffer(&self.buffers.interior, 0, bytemuck::bytes_of(&InteriorSlots::new(&self.topo)));
        let (strain, bend) = split_slots(&self.topo);
        q.write_buffer(&self.buffers.slots, 0, bytemuck::cast_slice(&strain));
        q.write_buffer(&self.buffers.bend_slots, 0, bytemuck::cast_slice(&bend));
        let (a, b) = spring_halves(&self.topo.springs);
        q.write_buffer(&self.buffers.springs, 0, bytemuck::cast_slice(a));
        q.write_buffer(&self.buffers.springs_b, 0, bytemuck::cast_slice(b));
        self.recipe = recipe(self.variant, params.strain_iterations, self.caps);
        self.params = params;
        Ok(())
    }

    fn set_grab(&mut self, grab: Option<Grab>) {
        self.grab = Grab::checked(grab, self.topo.num_particles());
    }

    fn step_frame(&mut self) -> Result<(), SolverError> {
        let t0 = Instant::now();
        self.sp = StepParams::new(&self.params, &self.scene, self.grab);
        self.ctx.queue.write_buffer(&self.buffers.params, 0, bytemuck::bytes_of(&self.sp));
        let recipe = self.recipe.clone();
        // Query indices run on across the frame's submissions; the timestamps are read
        // back once, after the last one.
        let (mut q, mut labels) = (0, Vec::new());
        let submissions = match self.variant {
            Variant::Optimized => 1,
            Variant::Naive => self.params.substeps,
        };
        // CPU-side cost: encoding (passes, finish) and queue.submit, per frame.
        let (mut record_ns, mut submit_ns) = (0.0, 0.0);
        for _ in 0..submissions {
            let t_record = Instant::now();
            let mut enc =
                self.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });
            for _ in 0..self.params.substeps / submissions {
                self.record(&mut enc, &recipe, &mut q, &mut labels);
            }
            let cmd = enc.finish();
            record_ns += t_record.elapsed().as_nanos() as f64;
            let t_submit = Instant::now();
            self.ctx.queue.submit([cmd]);
            submit_ns += t_submit.elapsed().as_nanos() as f64;
        }
        if self.time_kernels {
            self.timer.record(CPU_RECORD, record_ns);
            self.timer.record(CPU_SUBMIT, submit_ns);
        }
        let gpu_ns = self.read_times(q, &labels)?;
        let timed = gpu_ns.is_some();
        let gpu_ns = gpu_ns.unwrap_or(0.0);
        if self.time_kernels {
            if !timed {
                self.ctx.wait_idle().map_err(backend)?;
            }
            let frame = if timed { gpu_ns } else { t0.elapsed().as_nanos() as f64 };
            self.timer.record(FRAME, frame);
        }
        self.ctx.check("simulating a frame").map_err(backend)
    }

    fn state(&mut self) -> Result<ClothState, SolverError> {
        let np = self.topo.num_particles();
        let size = np as u64 * V4_SIZE;
        let read = |buf: &wgpu::Buffer| -> Result<Vec<V4>, SolverError> {
            let raw = self.ctx.read_buffer(buf, 0, size).map_err(backend)?;
            Ok(bytemuck::cast_slice::<u8, V4>(&raw).to_vec())
        };
        let b = &self.buffers;
        Ok(ClothState {
            n: self.topo.n,
            pos: read(&b.pos[self.cur])?,
            prev: read(&b.prev)?,
            force: read(&b.force)?,
            normal: read(&b.normal)?,
        })
    }

    fn set_state(&mut self, state: &ClothState) -> Result<(), SolverError> {
        state.check(self.topo.n)?;
        let q = &self.ctx.queue;
        let b = &self.buffers;
        q.write_buffer(&b.pos[self.cur], 0, bytemuck::cast_slice(&state.pos));
        q.write_buffer(&b.prev, 0, bytemuck::cast_slice(&state.prev));
        q.write_buffer(&b.force, 0, bytemuck::cast_slice(&state.force));
        q.write_buffer(&b.normal, 0, bytemuck::cast_slice(&state.normal));
        Ok(())
    }

    fn timings(&self) -> KernelTimings {
        self.timer.table()
    }

    fn reset_timings(&mut self) {
        self.timer.clear();
    }

    fn set_kernel_timing(&mut self, on: bool) {
        self.time_kernels = on;
    }
}
