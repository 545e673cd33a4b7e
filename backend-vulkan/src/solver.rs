//! The Vulkan solver: device-local buffers, one descriptor set per kernel and position
//! parity, and the recipes of clothlab-shaders recorded into one command buffer per frame
//! (optimized) or one per substep, submitted without waiting in between (naive), with a
//! compute→compute barrier between dependent dispatches. Options: per-substep statistics
//! by subgroup reductions or by atomics, and the spring table read from storage buffers,
//! from a sampled image, or (default) from a uniform block in the interior.

use std::collections::HashMap;
use std::sync::Arc;
use std::time::Instant;

use ash::vk;
use clothlab_core::cpu::SubstepStats;
use clothlab_core::grid::{
    ClothState, ClothTopology, Grab, InteriorSlots, STRAIN_SLOTS, SpringSlot, StepParams, V4, build, spring_constants,
};
use clothlab_core::layout::{Buf, TABLE_WIDTH};
use clothlab_core::params::MAX_SUBSTEPS;
use clothlab_core::scene::{Aabb, MAX_COLLIDERS, Scene, Sphere};
use clothlab_core::solver::{Solver, SolverError};
use clothlab_core::timing::{CPU_RECORD, CPU_SUBMIT, FRAME, KernelTimings, TimingRecorder};
use clothlab_core::{SimParams, cpu};
use clothlab_engine::kernels::{HostBuffers, Immediates, KernelRef, groups};
use clothlab_engine::recipe::{
    Caps, Command, Hazards, StatsMode, Variant, dispatches, kernels_for, kernels_of, recipe, res, stats_commands,
};
use clothlab_engine::tables::{record_times, split_slots, spring_halves, table_texels};
use clothlab_engine::validate::KernelRunner;
use gpu_allocator::MemoryLocation;

use crate::VkError;
use crate::raw::{self, Buffer, Commands, Device, Image, Kernel, Sets};

const STORAGE: vk::DescriptorType = vk::DescriptorType::STORAGE_BUFFER;
const UNIFORM: vk::DescriptorType = vk::DescriptorType::UNIFORM_BUFFER;
/// Timestamp queries per frame.
const MAX_QUERIES: u32 = 4096;
/// Where the frame's statistics land in the staging buffer (after the step constants).
const STATS_OFFSET: u64 = 256;

/// Where the gathers read the spring table from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SpringTable {
    /// Every particle takes its springs' constants from a uniform block and its neighbours
    /// by offset (border included) when the table is the regular grid's; the table is read
    /// (storage buffers) only for an irregular one.
    #[default]
    Interior,
    /// Every particle reads its slots from read-only storage buffers.
    Storage,
    /// Every particle reads its slots from a sampled image (the thesis's texture memory).
    Image,
}

/// How the Vulkan solver is set up.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct VulkanOptions {
    /// Run under the Khronos validation layer (when installed); any message fails the call.
    pub validation: bool,
    /// Per-substep statistics (max strain, kinetic energy) computed on the GPU.
    pub stats: StatsMode,
    /// Where the spring table is read from.
    pub table: SpringTable,
}

/// The buffers of the step, bound at the same numbers as in the WGSL (see shaders/wgsl).
struct Buffers {
    params: Buffer,
    pos: [Buffer; 2],
    prev: Buffer,
    force: Buffer,
    normal: Buffer,
    slots: Buffer,
    springs: Buffer,
    tethers: Buffer,
    triangles: Buffer,
    face_slots: Buffer,
    faces: Buffer,
    spheres: Buffer,
    boxes: Buffer,
    bend_slots: Buffer,
    springs_b: Buffer,
    interior: Buffer,
    stats_max: Buffer,
    stats_energy: Buffer,
    partials: Buffer,
    table: Option<Image>,
}

impl Buffers {
    /// (binding, type, buffer) for the descriptor set whose current positions are `pos[k]`.
    fn bindings(&self, k: usize) -> Vec<(u32, vk::DescriptorType, &Buffer)> {
        vec![
            (0, UNIFORM, &self.params),
            (1, STORAGE, &self.pos[k]),
            (2, STORAGE, &self.prev),
            (3, STORAGE, &self.force),
            (4, STORAGE, &self.normal),
            (5, STORAGE, &self.pos[1 - k]),
            (6, STORAGE, &self.slots),
            (7, STORAGE, &self.springs),
            (8, STORAGE, &self.tethers),
            (9, STORAGE, &self.triangles),
            (10, STORAGE, &self.face_slots),
            (11, STORAGE, &self.faces),
            (12, STORAGE, &self.spheres),
            (13, STORAGE, &self.boxes),
            (14, STORAGE, &self.bend_slots),
            (15, STORAGE, &self.springs_b),
            (16, UNIFORM, &self.interior),
            (17, STORAGE, &self.stats_max),
            (18, STORAGE, &self.stats_energy),
            (19, STORAGE, &self.partials),
        ]
    }
}

/// The cloth solver on raw Vulkan.
pub struct VulkanSolver {
    variant: Variant,
    scene: Scene,
    params: SimParams,
    grab: Option<Grab>,
    topo: ClothTopology,
    sp: StepParams,
    recipe: Vec<Command>,
    caps: Caps,
    options: VulkanOptions,
    stats: Vec<SubstepStats>,
    hazards: Hazards,
    barriers: usize,
    cur: usize,
    timer: TimingRecorder,
    /// Record per-dispatch GPU timestamps.
    pub time_kernels: bool,
    // Vulkan objects; each holds the device alive, and is dropped before it.
    kernels: HashMap<KernelRef, (Kernel, [vk::DescriptorSet; 2])>,
    sets: Sets,
    cmds: Commands,
    staging: Buffer,
    buffers: Buffers,
    dev: Arc<Device>,
}

fn backend(e: VkError) -> SolverError {
    match e {
        VkError::NoVulkan(_) | VkError::NoAdapter => SolverError::NoAdapter(e.to_string()),
        e => SolverError::Driver(e.to_string()),
    }
}

impl VulkanSolver {
    /// Builds the cloth of `scene` on the first Vulkan device with a compute queue; with
    /// `validation`, the Khronos validation layer checks every call (when installed).
    pub fn new(variant: Variant, scene: Scene, params: SimParams, validation: bool) -> Result<Self, SolverError> {
        Self::with_options(variant, scene, params, VulkanOptions { validation, ..Default::default() })
    }

    /// Builds the cloth of `scene` with `options` (statistics, spring-table source).
    pub fn with_options(
        variant: Variant,
        scene: Scene,
        params: SimParams,
        options: VulkanOptions,
    ) -> Result<Self, SolverError> {
        let dev = Device::new(options.validation).map_err(backend)?;
        Self::on_device(dev, variant, scene, params, options)
    }

    /// Builds the cloth on `dev` (a window's device: the presenter draws its buffers).
    /// `options.validation` is the device's business and ignored here.
    pub fn on_device(
        dev: Arc<Device>,
        variant: Variant,
        scene: Scene,
        params: SimParams,
        options: VulkanOptions,
    ) -> Result<Self, SolverError> {
        if scene.spheres.len() > MAX_COLLIDERS || scene.boxes.len() > MAX_COLLIDERS {
            return Err(SolverError::Invalid(format!("at most {MAX_COLLIDERS} spheres and boxes")));
        }
        if options.stats == StatsMode::Subgroups && !dev.subgroup_arithmetic {
            return Err(SolverError::Unsupported(format!(
                "{} has no subgroup arithmetic in compute shaders: use statistics by atomics",
                dev.name
            )));
        }
        let per_particle = (STRAIN_SLOTS * std::mem::size_of::<SpringSlot>()) as u64;
        SolverError::check_table(scene.cloth.n, per_particle, dev.max_storage_range, &dev.name)?;
        let (mut state, topo) = build(&scene, &params)?;
        let sp = StepParams::new(&params, &scene, None);
        let mut face = vec![[0.0f32; 4]; topo.triangles.len()];
        cpu::tri_normals(cpu::Exec::Serial, &topo.triangles, &state.pos, &mut face);
        cpu::vertex_normals(cpu::Exec::Serial, &sp, &topo.face_slots, &face, &mut state.normal, &mut state.force);

        let mut spheres = [Sphere { center: [0.0; 3], radius: 0.0 }; MAX_COLLIDERS];
        spheres[..scene.spheres.len()].copy_from_slice(&scene.spheres);
        let mut boxes = [Aabb::new([0.0; 3], [0.0; 3]); MAX_COLLIDERS];
        boxes[..scene.boxes.len()].copy_from_slice(&scene.boxes);
        let tri_flat: Vec<u32> = topo.triangles.iter().flatten().copied().collect();
        let face_flat: Vec<i32> = topo.face_slots.iter().flatten().copied().collect();
        let (strain, bend) = split_slots(&topo);
        let (springs_a, springs_b) = spring_halves(&topo.springs);
        let mut interior = InteriorSlots::new(&topo);
        if options.table != SpringTable::Interior {
            interior.enabled = 0;
        }
        let (texels, table_height) =
            if options.table == SpringTable::Image { table_texels(&topo) } else { (Vec::new(), 0) };
        let groups_xy = groups(topo.num_particles() as u32);
        let stats_zero = vec![0u8; 4 * MAX_SUBSTEPS as usize];
        let partials_zero = vec![0u8; 8 * (groups_xy.0 * groups_xy.1) as usize];

        // Everything device-local; filled through one staging buffer.
        let contents: Vec<(&str, &[u8], bool)> = vec![
            ("params", bytemuck::bytes_of(&sp), true),
            ("pos0", bytemuck::cast_slice(&state.pos), false),
            ("pos1", bytemuck::cast_slice(&state.pos), false),
            ("prev", bytemuck::cast_slice(&state.prev), false),
            ("force", bytemuck::cast_slice(&state.force), false),
            ("normal", bytemuck::cast_slice(&state.normal), false),
            ("slots", bytemuck::cast_slice(&strain), false),
            ("springs", bytemuck::cast_slice(springs_a), false),
            ("tethers", bytemuck::cast_slice(&topo.tethers), false),
            ("triangles", bytemuck::cast_slice(&tri_flat), false),
            ("face_slots", bytemuck::cast_slice(&face_flat), false),
            ("faces", bytemuck::cast_slice(&face), false),
            ("spheres", bytemuck::cast_slice(&spheres), false),
            ("boxes", bytemuck::cast_slice(&boxes), false),
            ("bend_slots", bytemuck::cast_slice(&bend), false),
            ("springs_b", bytemuck::cast_slice(springs_b), false),
            ("interior", bytemuck::bytes_of(&interior), true),
            ("stats_max", &stats_zero, false),
            ("stats_energy", &stats_zero, false),
            ("partials", &partials_zero, false),
        ];
        let largest = contents
            .iter()
            .map(|c| c.1.len() as u64)
            .chain([(texels.len() * 16) as u64, STATS_OFFSET + 8 * MAX_SUBSTEPS as u64])
            .max()
            .unwrap_or(4);
        let mut staging = Buffer::new(
            &dev,
            "staging",
            largest,
            vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::CpuToGpu,
        )
        .map_err(backend)?;
        let mut cmds = Commands::new(&dev, MAX_QUERIES).map_err(backend)?;
        let mut made = Vec::new();
        for (name, bytes, uniform) in &contents {
            // Positions and normals are the renderer's vertex buffers too (no copy).
            let drawn = matches!(*name, "pos0" | "pos1" | "normal");
            let usage =
                if *uniform { vk::BufferUsageFlags::UNIFORM_BUFFER } else { vk::BufferUsageFlags::STORAGE_BUFFER }
                    | if drawn { vk::BufferUsageFlags::VERTEX_BUFFER } else { vk::BufferUsageFlags::empty() }
                    | vk::BufferUsageFlags::TRANSFER_DST
                    | vk::BufferUsageFlags::TRANSFER_SRC;
            let b = Buffer::new(&dev, name, bytes.len() as u64, usage, MemoryLocation::GpuOnly).map_err(backend)?;
            upload(&mut cmds, &mut staging, &b, bytes).map_err(backend)?;
            made.push(b);
        }
        let mut it = made.into_iter();
        let mut next = || it.next().expect("one buffer per entry");
        let buffers = Buffers {
            params: next(),
            pos: [next(), next()],
            prev: next(),
            force: next(),
            normal: next(),
            slots: next(),
            springs: next(),
            tethers: next(),
            triangles: next(),
            face_slots: next(),
            faces: next(),
            spheres: next(),
            boxes: next(),
            bend_slots: next(),
            springs_b: next(),
            interior: next(),
            stats_max: next(),
            stats_energy: next(),
            partials: next(),
            table: None,
        };
        let mut buffers = buffers;
        if options.table == SpringTable::Image {
            let image = Image::new(&dev, "spring table", TABLE_WIDTH, table_height).map_err(backend)?;
            let map = staging.mapped().ok_or_else(|| SolverError::Driver("staging not host visible".into()))?;
            map[..texels.len() * 16].copy_from_slice(bytemuck::cast_slice(&texels));
            cmds.begin(0).map_err(backend)?;
            cmds.copy_to_image(&staging, &image);
            cmds.submit_and_wait(0).map_err(backend)?;
            buffers.table = Some(image);
        }
        // Push constants hold the step constants where the device has room (128 bytes is
        // the Vulkan minimum, so always in practice); the naive scatters use float atomics
        // where VK_EXT_shader_atomic_float is there, compare-exchange otherwise: the same
        // choice as on wgpu, so the naive pair compares only the APIs.
        let caps = Caps {
            float_atomics: dev.float_atomics,
            immediates: dev.max_push_constants as usize >= std::mem::size_of::<StepParams>(),
            table_image: options.table == SpringTable::Image,
        };
        let mut build: Vec<KernelRef> = kernels_for(caps);
        build.extend(dispatches(&stats_commands(options.stats, caps)));
        if caps.table_image {
            // The storage-table twins too, so that both homes of the table are checked.
            build.extend(kernels_for(Caps { table_image: false, ..caps }));
        }
        build.dedup();
        // Room for every kernel built now and for kernels added later (add_kernel).
        let sets = Sets::new(&dev, 2 * (build.len() as u32 + EXTRA_KERNELS)).map_err(backend)?;
        let mut solver = Self {
            variant,
            scene,
            params: params.clone(),
            grab: None,
            recipe: recipe(variant, params.strain_iterations, caps),
            caps,
            options,
            stats: Vec::new(),
            hazards: Hazards::default(),
            barriers: 0,
            topo,
            sp,
            cur: 0,
            timer: TimingRecorder::default(),
            time_kernels: true,
            kernels: HashMap::new(),
            sets,
            cmds,
            staging,
            buffers,
            dev,
        };
        for k in build {
            solver.build(k)?;
        }
        solver.check()?;
        Ok(solver)
    }

    /// Builds the pipeline and the two descriptor sets (one per position parity) of `k`.
    fn build(&mut self, k: KernelRef) -> Result<(), SolverError> {
        if self.kernels.contains_key(&k) {
            return Ok(());
        }
        if self.kernels.len() as u32 >= self.sets.capacity() / 2 {
            return Err(SolverError::Shader {
                kernel: k.shader_name(),
                reason: format!("at most {EXTRA_KERNELS} kernels can be added to a Vulkan solver"),
            });
        }
        let spirv = k.spirv()?;
        let b = &self.buffers;
        let mut layout: Vec<(u32, vk::DescriptorType)> = b.bindings(0).iter().map(|(b, t, _)| (*b, *t)).collect();
        let image = match (&b.table, k.flavor.table_image) {
            (Some(i), true) => Some((Buf::Table.binding(), i)),
            (None, true) => {
                return Err(SolverError::Shader {
                    kernel: k.shader_name(),
                    reason: "built without the table image".into(),
                });
            }
            _ => None,
        };
        if image.is_some() {
            layout.push((Buf::Table.binding(), vk::DescriptorType::SAMPLED_IMAGE));
        }
        let push = if k.step_immediates() {
            std::mem::size_of::<StepParams>() as u32
        } else if k.def.immediates == Immediates::Substep {
            4
        } else {
            0
        };
        let kernel = Kernel::new(&self.dev, &spirv, &layout, push).map_err(backend)?;
        let s0 = self.sets.allocate(&kernel, &b.bindings(0), image).map_err(backend)?;
        let s1 = self.sets.allocate(&kernel, &b.bindings(1), image).map_err(backend)?;
        self.kernels.insert(k, (kernel, [s0, s1]));
        Ok(())
    }

    /// The device's name.
    pub fn adapter(&self) -> String {
        self.dev.name.clone()
    }

    /// Whether the naive scatters use float atomics (VK_EXT_shader_atomic_float).
    pub fn float_atomics(&self) -> bool {
        self.dev.float_atomics
    }

    /// Validation-layer messages gathered since the last call (none when it is off).
    pub fn take_validation_messages(&self) -> Vec<String> {
        self.dev.take_messages()
    }

    /// The kernels one substep dispatches, in order (statistics included).
    pub fn recipe_kernels(&self) -> Vec<KernelRef> {
        kernels_of(&self.substep_recipe())
    }

    /// The commands of one substep (statistics included).
    pub fn commands(&self) -> Vec<Command> {
        self.substep_recipe()
    }

    /// The options it was built with.
    pub fn options(&self) -> VulkanOptions {
        self.options
    }

    /// Invocations per subgroup on this device (0 when unknown).
    pub fn subgroup_size(&self) -> u32 {
        self.dev.subgroup_size
    }

    /// Whether timestamps and barriers use synchronization2 (Vulkan 1.3).
    pub fn sync2(&self) -> bool {
        self.dev.sync2
    }

    /// The current positions and the normals: the renderer's vertex buffers.
    pub fn vertex_buffers(&self) -> (&Buffer, &Buffer) {
        (&self.buffers.pos[self.cur], &self.buffers.normal)
    }

    /// Pipeline barriers recorded in the last frame.
    pub fn barriers_last_frame(&self) -> usize {
        self.barriers
    }

    /// Records a barrier and notes it.
    fn barrier(&mut self) {
        self.cmds.barrier();
        self.hazards.clear();
        self.barriers += 1;
    }

    /// The device, for checks that outlive the solver (the leak check).
    pub fn device(&self) -> Arc<Device> {
        self.dev.clone()
    }

    /// The commands of one substep: the step, then the statistics.
    fn substep_recipe(&self) -> Vec<Command> {
        let mut r = self.recipe.clone();
        r.extend(stats_commands(self.options.stats, self.caps));
        r
    }

    /// Records `commands` of substep `substep` (each after the barrier it needs),
    /// timestamps from query `*q` while timing.
    fn record(&mut self, commands: &[Command], substep: u32, q: &mut u32, labels: &mut Vec<&'static str>) {
        let substep_bytes = substep.to_le_bytes();
        for c in commands {
            // Only the barriers the data needs (see recipe::Hazards).
            let mut cur = self.cur;
            if self.hazards.command(c, &mut cur) {
                self.cmds.barrier();
                self.barriers += 1;
            }
            self.cur = cur;
            let k = match c {
                Command::Clear(buf) => {
                    if let Some(b) = self.buffers.get(*buf, self.cur) {
                        self.cmds.zero(b);
                    }
                    continue;
                }
                Command::Swap => continue,
                Command::Dispatch(k) => *k,
            };
            let (kernel, sets) = &self.kernels[&k];
            let push: &[u8] = if k.step_immediates() {
                bytemuck::bytes_of(&self.sp)
            } else if k.def.immediates == Immediates::Substep {
                &substep_bytes
            } else {
                &[]
            };
            let timed = self.time_kernels && self.dev.timestamps && *q + 2 <= MAX_QUERIES;
            let d = raw::Dispatch { kernel, set: sets[self.cur], push, groups: groups(k.def.count.of(&self.topo)) };
            self.cmds.dispatch(&d, timed.then_some(*q));
            if timed {
                *q += 2;
                labels.push(k.def.label);
            }
        }
    }

    /// Submits, waits, records the timestamps; returns the GPU span in ns when timed.
    fn submit(&mut self, q: u32, labels: &[&'static str]) -> Result<Option<f64>, SolverError> {
        let ticks = self.cmds.submit_and_wait(q).map_err(backend)?;
        self.check()?;
        if q == 0 {
            return Ok(None);
        }
        let per_substep = clothlab_engine::cpu::dispatch_count(&self.recipe);
        Ok(Some(record_times(&mut self.timer, labels, &ticks, self.dev.timestamp_period as f64, per_substep)))
    }

    /// Fails if the validation layer reported anything.
    fn check(&self) -> Result<(), SolverError> {
        let m = self.dev.take_messages();
        if m.is_empty() { Ok(()) } else { Err(backend(VkError::Validation(m.join(" | ")))) }
    }

    fn write(&mut self, which: Target, bytes: &[u8]) -> Result<(), SolverError> {
        self.hazards.dirty();
        let dst = target(&self.buffers, which, self.cur)?;
        upload(&mut self.cmds, &mut self.staging, dst, bytes).map_err(backend)
    }

    fn read(&mut self, which: Target) -> Result<Vec<V4>, SolverError> {
        let buf = target(&self.buffers, which, self.cur)?;
        let bytes = download(&mut self.cmds, &mut self.staging, buf, buf.size).map_err(backend)?;
        Ok(bytes.chunks_exact(16).map(bytemuck::pod_read_unaligned::<V4>).collect())
    }

    /// Uploads `bufs` and `sp`, runs `commands`, reads the buffers back (see
    /// [`KernelRunner::run_commands`]).
    fn run_host(&mut self, commands: &[Command], sp: &StepParams, bufs: &mut HostBuffers) -> Result<(), SolverError> {
        bufs.check(&self.topo, sp)?;
        for k in dispatches(commands) {
            self.build(k)?;
        }
        self.write(Target::Params, bytemuck::bytes_of(sp))?;
        self.sp = *sp;
        for buf in HOST_BUFFERS {
            if let Some(v) = bufs.get(buf) {
                self.write(Target::Buf(buf), bytemuck::cast_slice(v))?;
            }
        }
        let was = self.time_kernels;
        self.time_kernels = false;
        self.cmds.begin(0).map_err(backend)?;
        self.record(commands, 0, &mut 0, &mut Vec::new());
        let r = self.submit(0, &[]);
        self.time_kernels = was;
        r?;
        for buf in HOST_BUFFERS {
            let v = self.read(Target::Buf(buf))?;
            if let Some(dst) = bufs.get_mut(buf) {
                *dst = v;
            }
        }
        Ok(())
    }
}

/// The buffers a kernel test or a bisection moves between host and device.
const HOST_BUFFERS: [Buf; 6] = [Buf::Pos, Buf::PosOut, Buf::Prev, Buf::Force, Buf::Normal, Buf::Faces];

/// Kernels that can be added to a solver after it is built (descriptor sets are set
/// aside for them).
const EXTRA_KERNELS: u32 = 16;

/// A buffer the host writes or reads.
#[derive(Clone, Copy)]
enum Target {
    Params,
    /// A step buffer, the position pair by the current parity.
    Buf(Buf),
}

fn target(b: &Buffers, which: Target, cur: usize) -> Result<&Buffer, SolverError> {
    match which {
        Target::Params => Ok(&b.params),
        Target::Buf(buf) => b.get(buf, cur).ok_or_else(|| SolverError::Driver(format!("no buffer {buf:?}"))),
    }
}

impl Buffers {
    /// The buffer bound as `buf` when the current positions are `pos[cur]`.
    /// (Only the buffers the host or a clear touches; the tables are bound, never moved.)
    fn get(&self, buf: Buf, cur: usize) -> Option<&Buffer> {
        Some(match buf {
            Buf::Params => &self.params,
            Buf::Pos => &self.pos[cur],
            Buf::PosOut => &self.pos[1 - cur],
            Buf::Prev => &self.prev,
            Buf::Force => &self.force,
            Buf::Normal => &self.normal,
            Buf::Faces => &self.faces,
            Buf::StatsMax => &self.stats_max,
            Buf::StatsEnergy => &self.stats_energy,
            _ => return None,
        })
    }
}

/// Copies `bytes` into `dst` through the staging buffer.
pub(crate) fn upload(cmds: &mut Commands, staging: &mut Buffer, dst: &Buffer, bytes: &[u8]) -> Result<(), VkError> {
    let map = staging
        .mapped()
        .ok_or(VkError::Vulkan { what: "mapping the staging buffer", reason: "not host visible".into() })?;
    map[..bytes.len()].copy_from_slice(bytes);
    cmds.begin(0)?;
    cmds.copy(staging, dst, bytes.len() as u64);
    cmds.submit_and_wait(0).map(|_| ())
}

/// Reads `size` bytes of `src` through the staging buffer.
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

impl KernelRunner for VulkanSolver {
    fn kernels(&self) -> Vec<KernelRef> {
        let mut v: Vec<KernelRef> = self.kernels.keys().copied().collect();
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
        self.dev.name.clone()
    }

    fn add_kernel(&mut self, kernel: KernelRef) -> Result<(), SolverError> {
        self.build(kernel)?;
        self.check()
    }
}

impl Solver for VulkanSolver {
    fn name(&self) -> &str {
        match self.variant {
            Variant::Naive => "vulkan-naive",
            Variant::Optimized => "vulkan",
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
        // Spring constants depend on dt and the stiffness fractions: rewrite the tables in
        // place (the descriptor sets keep pointing at the same buffers).
        let (strain, bend) = split_slots(&self.topo);
        let (a, b) = spring_halves(&self.topo.springs);
        let mut interior = InteriorSlots::new(&self.topo);
        if self.options.table != SpringTable::Interior {
            interior.enabled = 0;
        }
        if let Some(image) = &self.buffers.table {
            let (texels, _) = table_texels(&self.topo);
            let map = self.staging.mapped().ok_or_else(|| SolverError::Driver("staging not host visible".into()))?;
            map[..texels.len() * 16].copy_from_slice(bytemuck::cast_slice(&texels));
            self.cmds.begin(0).map_err(backend)?;
            self.cmds.copy_to_image(&self.staging, image);
            self.cmds.submit_and_wait(0).map_err(backend)?;
        }
        for (buf, bytes) in [
            (&self.buffers.slots, bytemuck::cast_slice::<SpringSlot, u8>(&strain)),
            (&self.buffers.bend_slots, bytemuck::cast_slice(&bend)),
            (&self.buffers.springs, bytemuck::cast_slice(a)),
            (&self.buffers.springs_b, bytemuck::cast_slice(b)),
            (&self.buffers.interior, bytemuck::bytes_of(&interior)),
        ] {
            upload(&mut self.cmds, &mut self.staging, buf, bytes).map_err(backend)?;
        }
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
        // The frame's constants go through the staging buffer in the frame's own command
        // buffer (a copy and a barrier before the first dispatch), not in a submission of
        // their own.
        let bytes = bytemuck::bytes_of(&self.sp);
        let map = self.staging.mapped().ok_or_else(|| SolverError::Driver("staging buffer not host visible".into()))?;
        map[..bytes.len()].copy_from_slice(bytes);
        let recipe = self.substep_recipe();
        let stats = self.options.stats != StatsMode::Off;
        let substeps = self.params.substeps;
        // Optimized: one command buffer for the frame. Naive: one per substep, submitted
        // without waiting; the last is fenced, and its fence covers all of them.
        let submissions = match self.variant {
            Variant::Optimized => 1,
            Variant::Naive => substeps,
        };
        let per_submission = substeps / submissions;
        let max_q =
            if self.time_kernels { (2 * substeps as usize * recipe.len()).min(MAX_QUERIES as usize) as u32 } else { 0 };
        let (mut q, mut labels) = (0, Vec::new());
        let (mut record_ns, mut submit_ns) = (0.0, 0.0);
        self.cmds.reserve(submissions as usize).map_err(backend)?;
        self.barriers = 0;
        for k in 0..submissions {
            let t_record = Instant::now();
            self.cmds.begin_at(k as usize, if k == 0 { max_q } else { 0 }).map_err(backend)?;
            if k == 0 {
                self.cmds.copy(&self.staging, &self.buffers.params, std::mem::size_of::<StepParams>() as u64);
                let mut written = res::PARAMS;
                if stats {
                    self.cmds.zero(&self.buffers.stats_max);
                    self.cmds.zero(&self.buffers.stats_energy);
                    written |= res::STATS;
                }
                // One barrier after all earlier work (the renderer may still have been
                // reading the positions as vertices) and the copies above.
                self.hazards.add(0, written);
                self.cmds.barrier_after_all();
                self.hazards.clear();
                self.barriers += 1;
            }
            for s in 0..per_submission {
                self.record(&recipe, k * per_submission + s, &mut q, &mut labels);
            }
            let last = k + 1 == submissions;
            if last && stats {
                // The statistics land in the staging buffer, read after the wait.
                if self.hazards.conflicts(res::STATS, 0) {
                    self.barrier();
                }
                self.hazards.add(res::STATS, 0);
                let size = 4 * substeps as u64;
                self.cmds.copy_range(&self.buffers.stats_max, 0, &self.staging, STATS_OFFSET, size);
                self.cmds.copy_range(&self.buffers.stats_energy, 0, &self.staging, STATS_OFFSET + size, size);
            }
            record_ns += t_record.elapsed().as_nanos() as f64;
            let t_submit = Instant::now();
            self.cmds.submit(last).map_err(backend)?;
            submit_ns += t_submit.elapsed().as_nanos() as f64;
        }
        let ticks = self.cmds.wait(q).map_err(backend)?;
        self.check()?;
        if stats {
            let map =
                self.staging.mapped().ok_or_else(|| SolverError::Driver("staging buffer not host visible".into()))?;
            let words: &[u8] = &map[STATS_OFFSET as usize..(STATS_OFFSET + 8 * substeps as u64) as usize];
            let word =
                |k: usize| f32::from_le_bytes([words[4 * k], words[4 * k + 1], words[4 * k + 2], words[4 * k + 3]]);
            let n = substeps as usize;
            self.stats = (0..n).map(|k| SubstepStats { max_strain: word(k), kinetic_energy: word(n + k) }).collect();
        }
        if self.time_kernels {
            self.timer.record(CPU_RECORD, record_ns);
            self.timer.record(CPU_SUBMIT, submit_ns);
            let gpu_ns = (q > 0).then(|| {
                record_times(
                    &mut self.timer,
                    &labels,
                    &ticks,
                    self.dev.timestamp_period as f64,
                    clothlab_engine::cpu::dispatch_count(&recipe),
                )
            });
            self.timer.record(FRAME, gpu_ns.unwrap_or_else(|| t0.elapsed().as_nanos() as f64));
        }
        Ok(())
    }

    fn state(&mut self) -> Result<ClothState, SolverError> {
        Ok(ClothState {
            n: self.topo.n,
            pos: self.read(Target::Buf(Buf::Pos))?,
            prev: self.read(Target::Buf(Buf::Prev))?,
            force: self.read(Target::Buf(Buf::Force))?,
            normal: self.read(Target::Buf(Buf::Normal))?,
        })
    }

    fn set_state(&mut self, state: &ClothState) -> Result<(), SolverError> {
        state.check(self.topo.n)?;
        self.write(Target::Buf(Buf::Pos), bytemuck::cast_slice(&state.pos))?;
        self.write(Target::Buf(Buf::Prev), bytemuck::cast_slice(&state.prev))?;
        self.write(Target::Buf(Buf::Force), bytemuck::cast_slice(&state.force))?;
        self.write(Target::Buf(Buf::Normal), bytemuck::cast_slice(&state.normal))?;
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

    fn substep_stats(&self) -> Vec<SubstepStats> {
        self.stats.clone()
    }
}
