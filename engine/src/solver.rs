//! The one GPU solver: [`GpuSolver`] implements [`Solver`] and [`KernelRunner`] once, for
//! any [`Engine`] — buffers from the step's binding table, the recipe of the variant
//! recorded with the barriers its hazards need, one submission per frame (optimized) or
//! per substep (naive), per-kernel timestamps, NaN-poisoned kernel checks, statistics, and
//! parameter changes that rewrite the spring tables in place.

use std::time::Instant;

use clothlab_core::build;
use clothlab_core::grid::{
    ClothState, ClothTopology, Grab, GridSpringConstants, STRAIN_SLOTS, SpringSlot, V4, spring_constants,
};
use clothlab_core::layout::{ADJ_ROWS, Buf, Uses};
use clothlab_core::params::MAX_SUBSTEPS;
use clothlab_core::pins::{MAX_PIN_GROUPS, PinPose, PinSlot};
use clothlab_core::scene::{Aabb, MAX_COLLIDERS, Scene, Sphere};
use clothlab_core::step_params::StepParams;
use clothlab_core::timing::{CPU_RECORD, CPU_SUBMIT, FRAME, KernelTimings, TimingRecorder};
use clothlab_core::{SimParams, Solver, SolverError};
use clothlab_cpu::{self as twins, SubstepStats};

use crate::cpu::start_buffers;
use crate::gpu::{BufferId, Dispatch, Engine};
use crate::kernels::{HostBuffers, Immediates, KernelRef, groups};
use crate::recipe::KernelRunner;
use crate::recipe::{
    Caps, Command, Hazards, Integration, StatsMode, bits, dispatches, frame_end, kernels_for, kernels_of, recipe_for,
    res, stats_commands,
};
use crate::tables::{adjacency, face_flat, record_times, sdf_texels, split_slots, spring_halves, table_texels};
use crate::variant::{Colliders, Constants, Draw, Sdf, Specialize, Submit, Table, Variant, VariantSpec};

/// Timestamp queries per frame.
pub const MAX_QUERIES: u32 = 4096;

/// What a GPU solver computes besides the step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SolverOptions {
    /// Per-substep statistics (max strain, kinetic energy) computed on the GPU.
    pub stats: StatsMode,
}

/// The buffers a kernel test or a bisection moves between host and device for
/// `commands`: the state and the face normals, and the integrators' scratch buffers and
/// CG scalars only when a command touches them (a Verlet bisection moves no more than
/// before there were any).
fn host_buffers(commands: &[Command]) -> Vec<Buf> {
    let touches = |what: &dyn Fn(&Buf) -> bool| {
        commands.iter().any(|c| match c {
            Command::Dispatch(k) | Command::Range { kernel: k, .. } => k.def.reads.iter().chain(k.def.writes).any(what),
            Command::Clear(b) => what(b),
            Command::Swap => false,
        })
    };
    let mut v = vec![Buf::Pos, Buf::PosOut, Buf::Vel, Buf::Force, Buf::Normal, Buf::Faces];
    if touches(&|b| Buf::AUX.contains(b) || *b == Buf::Scalars) {
        v.extend(Buf::AUX);
        v.push(Buf::Scalars);
    }
    if touches(&|b| matches!(b, Buf::TriFloats | Buf::TriInts | Buf::TriPairs)) {
        v.extend([Buf::TriFloats, Buf::TriInts, Buf::TriPairs]);
    }
    if touches(&|b| *b == Buf::Adjoint) {
        v.push(Buf::Adjoint);
    }
    v
}

/// The cloth solver on any [`Engine`].
pub struct GpuSolver<E: Engine> {
    engine: E,
    name: String,
    variant: Variant,
    options: SolverOptions,
    scene: Scene,
    params: SimParams,
    grab: Option<Grab>,
    topo: ClothTopology,
    /// The step constants of the frame being recorded (for kernels reading immediates).
    step_params: StepParams,
    recipe: Vec<Command>,
    /// What runs once after the frame's last substep (recipe::frame_end).
    frame_end: Vec<Command>,
    caps: Caps,
    /// Every buffer by binding; the position pair as `[pos0, pos1]`.
    ids: Vec<(Buf, BufferId)>,
    pos: [BufferId; 2],
    /// Which of `pos` holds the current positions.
    current_pos: usize,
    /// The renderer's own vertex buffers (positions, normals) with `draw=copy`.
    draw: Option<[BufferId; 2]>,
    hazards: Hazards,
    barriers: usize,
    stats: Vec<SubstepStats>,
    timer: TimingRecorder,
    time_kernels: bool,
    /// Substeps one recording of the recipe advances (`temporal=on`: the tiles' several
    /// per dispatch; 1 otherwise).
    substeps_per_recording: u32,
    /// Simulated time, s (moving colliders are written at every substep's).
    time: f64,
    /// Whether it has the contact between triangles' buffers ([`has_tri_buffers`]).
    tri_buffers: bool,
    /// What the contact between triangles did in the last frame's last substep (read
    /// back at the frame's end where the parameters use it).
    contact: Option<clothlab_core::solver::ContactStats>,
    /// Searches for the contact's pairs so far (the kernels search every substep).
    searches: u64,
    /// Every kernel it can run ([`KernelRunner::kernels`]): its recipe's, built when it
    /// starts, and the plain flavor of every kernel of the step, built when first run.
    offered: Vec<KernelRef>,
    /// Each world's parameters (one: a single run; world 0's are `params`). A batch's
    /// worlds lie world after world in the per-particle buffers and run in every
    /// dispatch's z ([`crate::worlds`]).
    worlds: Vec<SimParams>,
    /// Each world's simulated time, s (a batch's worlds step together; `time` is the
    /// clock of the colliders and pins, which every world of a moving scene shares).
    times: Vec<f64>,
    /// A batch's pin groups, world by world (a script moves each world's own; world 0's
    /// are the scene's too); empty in a single run, whose are the scene's.
    world_pins: Vec<Vec<clothlab_core::PinGroup>>,
    /// The substeps a frame's pin poses have room for: every count up to MAX_SUBSTEPS in
    /// a single run, the batch's own in a batch (a block per substep and world).
    pose_substeps: u32,
}

/// Substeps per recording of `variant`'s recipe on `topo` with `params`, refused with
/// per-substep statistics (a dispatch of several substeps has no statistics between them).
fn recipe_group(
    variant: &Variant,
    params: &SimParams,
    topo: &ClothTopology,
    options: SolverOptions,
    scene: &Scene,
) -> Result<u32, SolverError> {
    let group = crate::recipe::dispatch_substeps(variant, Integration::of(params), params.strain_iterations, topo);
    if group > 1 && options.stats != StatsMode::Off {
        return Err(SolverError::Unsupported(format!(
            "temporal=on advances {group} substeps per dispatch: per-substep statistics need temporal=off"
        )));
    }
    if group > 1 && scene.animated() {
        return Err(SolverError::Unsupported(format!(
            "temporal=on advances {group} substeps per dispatch with one pose of the colliders and pins: moving colliders or pins need temporal=off"
        )));
    }
    Ok(group)
}

/// Cloths of at most this many particles get the contact between triangles' buffers
/// whether or not their parameters use it (about 1.1 KiB a particle: 18 MiB at 128 ×
/// 128), so that the app's switch finds them. Larger cloths get them only when built
/// with that contact.
pub const TRI_BUFFERS_ALWAYS: usize = 128 * 128;

/// Whether the solver of `topo` built with `params` has the contact between triangles'
/// buffers.
fn has_tri_buffers(topo: &ClothTopology, params: &SimParams) -> bool {
    params.self_collision.triangles() || topo.num_particles() <= TRI_BUFFERS_ALWAYS
}

/// Whether a single run's solver of `topo` has the adjoint's planes ([`Buf::Adjoint`],
/// 128 bytes a particle): the cloths that get the contact between triangles' buffers
/// whatever their parameters.
pub fn has_adjoint(topo: &ClothTopology) -> bool {
    topo.num_particles() <= TRI_BUFFERS_ALWAYS
}

/// Refuses the contact between triangles on a solver built without its buffers.
fn check_contact(topo: &ClothTopology, built_with: bool, params: &SimParams) -> Result<(), SolverError> {
    if params.self_collision.triangles() && !built_with {
        return Err(SolverError::Unsupported(format!(
            "self_collision = \"triangles\" on a GPU cloth of {} particles is set when the solver is built (its buffers are made then for cloths over {TRI_BUFFERS_ALWAYS}): start with it",
            topo.num_particles()
        )));
    }
    Ok(())
}

/// The contact between triangles' buffers' first contents: the edges with their header,
/// zeroed starts, integers and pairs; one zero element each where `on` is false.
fn tri_contents(topo: &ClothTopology, on: bool, envs: usize) -> [(Buf, Vec<u8>); 4] {
    let zeros = |words: usize| vec![0u8; 16 * words.div_ceil(4).max(1)];
    if !on {
        return [Buf::TriEdges, Buf::TriFloats, Buf::TriInts, Buf::TriPairs].map(|b| (b, zeros(1)));
    }
    let l = clothlab_cpu::tri_contact::TriLayout::of(topo);
    let mut edges = l.edges_words(topo.edges());
    edges.resize(edges.len().div_ceil(4) * 4, 0);
    [
        (Buf::TriEdges, bytemuck::cast_slice(&edges).to_vec()),
        (Buf::TriFloats, zeros(4 * l.np * envs)),
        (Buf::TriInts, zeros(l.words() * envs)),
        (Buf::TriPairs, zeros(l.pair_words() * envs)),
    ]
}

impl<E: Engine> GpuSolver<E> {
    /// Builds the cloth of `scene` on `engine`, stepped by `variant` (a preset falls back
    /// to what the adapter has; a switch set explicitly is refused where it lacks it).
    pub fn new(
        engine: E,
        variant: impl Into<VariantSpec>,
        scene: Scene,
        params: SimParams,
        options: SolverOptions,
    ) -> Result<Self, SolverError> {
        Self::new_worlds(engine, variant, scene, vec![params], options)
    }

    /// A batch: the cloth of `scene` once per element of `worlds` (its parameters), every
    /// world in the same buffers and every kernel dispatched once for all of them
    /// ([`crate::worlds`]: what may differ between worlds, what a batch refuses). One
    /// element is [`GpuSolver::new`].
    pub fn new_worlds(
        mut engine: E,
        variant: impl Into<VariantSpec>,
        scene: Scene,
        worlds: Vec<SimParams>,
        options: SolverOptions,
    ) -> Result<Self, SolverError> {
        let Some(params) = worlds.first().cloned() else {
            return Err(SolverError::Invalid("a batch of no worlds".into()));
        };
        let envs = worlds.len();
        if scene.spheres.len() > MAX_COLLIDERS
            || scene.boxes.len() > MAX_COLLIDERS
            || scene.rods.len() > clothlab_core::sdf::MAX_RODS
        {
            return Err(SolverError::Invalid(format!(
                "at most {MAX_COLLIDERS} spheres, {MAX_COLLIDERS} boxes and {} rods (capsules, cylinders together)",
                clothlab_core::sdf::MAX_RODS
            )));
        }
        let info = engine.info().clone();
        // Immediates hold the step constants where the device has room; the scatters use
        // float atomics where the device has them, compare-exchange otherwise: the same
        // choice on every API, so that one variant on two APIs compares only the APIs.
        let caps = Caps {
            float_atomics: info.float_atomics,
            immediates: info.immediates,
            table_image: info.table_image,
            subgroups: info.subgroup_shuffle,
            grid: !scene.cloth.is_mesh(),
            tile: info.workgroup_memory >= crate::kernels::TILE_WORKGROUP_BYTES,
            sdf_image: info.sdf_image,
            cpu: info.cpu,
        };
        let variant = variant.into().resolve(&caps, info.api).map_err(|e| SolverError::Unsupported(e.0))?;
        if options.stats == StatsMode::Subgroups && !info.subgroup_arithmetic {
            return Err(SolverError::Unsupported(format!(
                "{} has no subgroup arithmetic in compute shaders on {}: use statistics by atomics",
                info.adapter, info.api
            )));
        }
        // Refuse a grid whose buffers the adapter cannot bind, naming the size it can take
        // (the largest buffer is the structural and shear half of the spring table).
        let per_particle = (STRAIN_SLOTS * std::mem::size_of::<SpringSlot>()) as u64;
        SolverError::check_table(scene.cloth.n, per_particle, info.max_binding, &info.adapter)?;
        let (state, topo) = build(&scene, &params)?;
        if envs > 1 {
            crate::worlds::check_batch(&scene, &topo, &worlds, options.stats, &info)?;
        }
        // A batch makes them only for the contact it runs (every world's, world after world).
        let tri_buffers = if envs > 1 { params.self_collision.triangles() } else { has_tri_buffers(&topo, &params) };
        check_contact(&topo, tri_buffers, &params)?;
        let tri = tri_contents(&topo, tri_buffers, envs);
        // A mesh's table in two bindings (its rows split by entries, whole rows each).
        let (first, second) = split_slots(&topo);
        let table_bytes = std::mem::size_of_val(first.as_slice()).max(std::mem::size_of_val(second.as_slice())) as u64;
        if topo.mesh.is_some() && table_bytes > info.max_binding {
            return Err(SolverError::Unsupported(format!(
                "a mesh of {} particles needs two {} MiB halves of its spring table; {} binds at most {} MiB",
                topo.num_particles(),
                table_bytes >> 20,
                info.adapter,
                info.max_binding >> 20
            )));
        }
        // Initial normals and wind, as every solver starts (each world with its own).
        let sp = StepParams::new(&params, &scene, None);
        let state = start_buffers(twins::Exec::Serial, &sp, &topo, &state);
        let mut per_world = crate::worlds::Starts::new(&state, &sp, envs, topo.num_particles());
        for p in &worlds[1..] {
            let (s, _) = build(&scene, p)?;
            let sp = StepParams::new(p, &scene, None);
            per_world.push(&start_buffers(twins::Exec::Serial, &sp, &topo, &s), &sp);
        }
        let state = per_world.state;
        let face = &state.faces;

        // The colliders at time 0, with their velocities (what the CPU engine's twins see:
        // the kernel checks run on these; a moving scene rewrites them every substep).
        let (mut at0, mut boxes0) = (Vec::new(), Vec::new());
        scene.colliders_at(0.0, &mut at0, &mut boxes0);
        let mut spheres = [Sphere::new([0.0; 3], 0.0); MAX_COLLIDERS];
        spheres[..at0.len()].copy_from_slice(&at0);
        let mut boxes = [Aabb::new([0.0; 3], [0.0; 3]); MAX_COLLIDERS];
        boxes[..boxes0.len()].copy_from_slice(&boxes0);
        let colours = topo.colours.words();
        let tri_flat: Vec<u32> = topo.triangles.iter().flatten().copied().collect();
        let face_flat = face_flat(&topo);
        let adjacency = adjacency(&topo);
        let (strain, bend) = (first, second);
        let (springs_a, springs_b) = spring_halves(&topo.springs);
        let interior = interior_block(&topo, variant.table);
        let (x, y) = groups(topo.num_particles() as u32);
        let stats_zero = vec![0u8; 4 * MAX_SUBSTEPS as usize];
        let partials_zero = vec![0u8; 8 * (x * y) as usize];
        let pos_bytes: &[u8] = bytemuck::cast_slice(&state.pos);
        let aux_zero = vec![0u8; 16 * envs * topo.num_particles()];
        // The adjoint's planes where the contact's buffers are made for any parameters
        // (`has_adjoint`), a single run's; one unused element elsewhere.
        let adjoint_zero =
            vec![0u8; 16 * if envs == 1 && has_adjoint(&topo) { ADJ_ROWS as usize * topo.num_particles() } else { 1 }];
        // The conjugate gradient's scalars, a vec4 a world.
        let scalars_zero = vec![0u8; 16 * envs];
        // Moving pins: their table, and room for a frame's poses at the most substeps (a
        // block of MAX_PIN_GROUPS a substep); none: one unused element each.
        // The unused element names no particle (a dispatch of no pins still runs one
        // workgroup, whose first invocation sees it and skips it).
        let no_pin = [PinSlot { rest: [0.0; 3], index: u32::MAX, group: 0, pad: [0; 3] }];
        let pin_slots: &[PinSlot] = if topo.pins.slots.is_empty() { &no_pin } else { &topo.pins.slots };
        // A batch's: a block per world for each of its substeps.
        let pose_substeps = if envs > 1 { params.substeps } else { MAX_SUBSTEPS };
        let pose_blocks = if topo.pins.slots.is_empty() { 1 } else { envs * pose_substeps as usize };
        let pin_poses = vec![0u8; pose_blocks * MAX_PIN_GROUPS * std::mem::size_of::<PinPose>()];
        // The capsules and bodies at time 0, then the bodies' fields (still ones stay).
        let mut shapes = scene.shapes_at(0.0);
        shapes.extend(clothlab_core::sdf::concat(&scene.bodies).0);
        // Positions and normals are the renderer's vertex buffers too (no copy).
        let contents: [(Buf, &[u8]); 40] = [
            (Buf::Params, sp.gpu_bytes()),
            (Buf::ParamsStorage, &per_world.params),
            (Buf::Contact, bytemuck::bytes_of(&sp.contact)),
            (Buf::SpheresUniform, bytemuck::cast_slice(&spheres)),
            (Buf::BoxesUniform, bytemuck::cast_slice(&boxes)),
            (Buf::Pos, pos_bytes),
            (Buf::PosOut, pos_bytes),
            (Buf::Vel, bytemuck::cast_slice(&state.vel)),
            (Buf::Force, bytemuck::cast_slice(&state.force)),
            (Buf::Normal, bytemuck::cast_slice(&state.normal)),
            (Buf::Slots, bytemuck::cast_slice(&strain)),
            (Buf::Springs, bytemuck::cast_slice(springs_a)),
            (Buf::Tethers, bytemuck::cast_slice(&topo.tethers)),
            (Buf::Triangles, bytemuck::cast_slice(&tri_flat)),
            (Buf::FaceSlots, bytemuck::cast_slice(face_flat)),
            (Buf::Adjacency, bytemuck::cast_slice(&adjacency)),
            (Buf::Colours, bytemuck::cast_slice(&colours)),
            (Buf::Faces, bytemuck::cast_slice(face)),
            (Buf::Spheres, bytemuck::cast_slice(&spheres)),
            (Buf::Boxes, bytemuck::cast_slice(&boxes)),
            (Buf::BendSlots, bytemuck::cast_slice(&bend)),
            (Buf::SpringsB, bytemuck::cast_slice(springs_b)),
            (Buf::Interior, bytemuck::bytes_of(&interior)),
            (Buf::StatsMax, &stats_zero),
            (Buf::StatsEnergy, &stats_zero),
            (Buf::Partials, &partials_zero),
            (Buf::Aux0, &aux_zero),
            (Buf::Aux1, &aux_zero),
            (Buf::Aux2, &aux_zero),
            (Buf::Aux3, &aux_zero),
            (Buf::Aux4, &aux_zero),
            (Buf::Scalars, &scalars_zero),
            (Buf::Pins, bytemuck::cast_slice(pin_slots)),
            (Buf::PinPoses, &pin_poses),
            (Buf::Shapes, bytemuck::cast_slice(&shapes)),
            (tri[0].0, &tri[0].1),
            (tri[1].0, &tri[1].1),
            (tri[2].0, &tri[2].1),
            (tri[3].0, &tri[3].1),
            (Buf::Adjoint, &adjoint_zero),
        ];
        let mut ids = Vec::with_capacity(contents.len());
        for (buf, bytes) in contents {
            let vertex = matches!(buf, Buf::Pos | Buf::PosOut | Buf::Normal);
            let label = match buf {
                Buf::Pos => "pos0",
                Buf::PosOut => "pos1",
                b => b.name(),
            };
            ids.push((buf, engine.create_buffer(buf, label, bytes, vertex)?));
        }
        // draw=copy: vertex buffers of the renderer's own, refreshed at every frame's end.
        let draw = if variant.draw == Draw::Copy {
            // World 0's: what a batch's renderer draws.
            let np = topo.num_particles();
            let normal_bytes: &[u8] = bytemuck::cast_slice(&state.normal[..np]);
            Some([
                engine.create_buffer(Buf::Pos, "draw pos", &pos_bytes[..16 * np], true)?,
                engine.create_buffer(Buf::Normal, "draw normal", normal_bytes, true)?,
            ])
        } else {
            None
        };
        let table_image = variant.table == Table::Image;
        if table_image {
            let (texels, height) = table_texels(&topo);
            engine.set_table_image(&texels, height)?;
        }
        if variant.sdf == Sdf::Image {
            let (texels, dims) = sdf_texels(&scene.bodies);
            engine.set_sdf_image(&texels, dims)?;
        }
        let id = |b: Buf| ids.iter().find(|(x, _)| *x == b).map(|(_, id)| *id).expect("every binding created");
        let pos = [id(Buf::Pos), id(Buf::PosOut)];
        let set = |k: usize| -> Vec<(Buf, BufferId)> {
            ids.iter()
                .map(|&(b, i)| match b {
                    Buf::Pos => (b, pos[k]),
                    Buf::PosOut => (b, pos[1 - k]),
                    _ => (b, i),
                })
                .collect()
        };
        engine.bind([set(0), set(1)])?;
        let uses = uses_of(&variant, &scene, &params);
        let step = specialised(recipe_for(&variant, params.strain_iterations, Integration::of(&params), &topo), uses);
        let group = recipe_group(&variant, &params, &topo, options, &scene)?;
        let end = specialised(frame_end(&variant, Integration::of(&params)), uses);
        let (step, end) = crate::worlds::in_worlds(step, end, envs)?;
        // Only what the frame dispatches is built now; the other kernels a validation may
        // run (`offered`) are built when first run (`run_host`): most are other
        // integrators' and other features', and building them all took a Vulkan solver's
        // start on lavapipe from 0.34 s to 1.16 s.
        let mut build_list: Vec<KernelRef> = kernels_of(&step);
        build_list.extend(kernels_of(&end));
        build_list.extend(dispatches(&stats_commands(options.stats, caps)));
        let mut offered = kernels_for(&variant);
        offered.extend(build_list.iter().copied());
        let name = variant.solver_name(info.api);
        let world_pins = if envs > 1 { vec![scene.pins.clone(); envs] } else { Vec::new() };
        let mut solver = Self {
            engine,
            name,
            variant,
            options,
            recipe: step,
            frame_end: end,
            scene,
            params,
            grab: None,
            topo,
            step_params: sp,
            caps,
            ids,
            pos,
            current_pos: 0,
            draw,
            hazards: Hazards::default(),
            barriers: 0,
            stats: Vec::new(),
            timer: TimingRecorder::default(),
            time_kernels: true,
            substeps_per_recording: group,
            time: 0.0,
            tri_buffers,
            contact: None,
            searches: 0,
            offered,
            world_pins,
            pose_substeps,
            worlds,
            times: vec![0.0; envs],
        };
        for k in build_list {
            solver.build(k)?;
        }
        solver.engine.check("creating the solver")?;
        Ok(solver)
    }

    /// Builds `k`'s pipeline (once), with room for the immediates it reads.
    fn build(&mut self, k: KernelRef) -> Result<(), SolverError> {
        let immediates = if k.step_immediates() {
            if !self.caps.immediates {
                return Err(SolverError::Shader {
                    kernel: k.shader_name(),
                    reason: format!("{} has no immediates", self.engine.info().adapter),
                });
            }
            StepParams::GPU_BYTES as u32
        } else if k.def.immediates == Immediates::Substep {
            4
        } else if k.def.immediates == Immediates::Range {
            8
        } else {
            0
        };
        if k.flavor.sdf_image && self.variant.sdf != Sdf::Image {
            return Err(SolverError::Shader {
                kernel: k.shader_name(),
                reason: "the bodies' distance-field image is uploaded only for sdf=image".into(),
            });
        }
        if k.flavor.table_image && self.variant.table != Table::Image {
            return Err(SolverError::Shader {
                kernel: k.shader_name(),
                reason: "the spring-table image is uploaded only for table=image".into(),
            });
        }
        self.engine.build(k, immediates)
    }

    /// Sets every world's parameters (`worlds`, one a world), refused with nothing changed
    /// where one world's are invalid or a batch's worlds differ where they share.
    fn apply_params(&mut self, worlds: Vec<SimParams>) -> Result<(), SolverError> {
        if worlds.len() != self.worlds.len() {
            return Err(SolverError::Invalid(format!(
                "{} parameter sets for {} worlds",
                worlds.len(),
                self.worlds.len()
            )));
        }
        for (k, p) in worlds.iter().enumerate() {
            let world =
                |e: SolverError| if worlds.len() > 1 { SolverError::Invalid(format!("world {k}: {e}")) } else { e };
            check_contact(&self.topo, self.tri_buffers, p).map_err(world)?;
            self.topo.validate_params(p).map_err(|e| world(e.into()))?;
            self.scene.check_motion_speed(p.dt()).map_err(|e| world(e.into()))?;
        }
        if worlds.len() > 1 {
            crate::worlds::check_batch(&self.scene, &self.topo, &worlds, self.options.stats, self.engine.info())?;
            if !self.topo.pins.slots.is_empty() && worlds[0].substeps > self.pose_substeps {
                return Err(SolverError::Unsupported(format!(
                    "a GPU batch with moving pins holds their poses for {} substeps a frame (its count when opened): {} need a new batch",
                    self.pose_substeps, worlds[0].substeps
                )));
            }
        }
        let params = worlds[0].clone();
        // A new dt keeps the velocity as it is: the state holds it, not Verlet's history.
        if spring_constants(&params, &self.topo) != spring_constants(&self.params, &self.topo) {
            // The spring constants depend on dt and the stiffness fractions: rewrite the
            // tables in place (the binding sets keep pointing at the same buffers). Wind,
            // gravity and the like reach the kernels with the next frame's constants.
            self.topo.set_spring_constants(&params);
            if self.variant.table == Table::Image {
                let (texels, height) = table_texels(&self.topo);
                self.engine.set_table_image(&texels, height)?;
            }
            let (strain, bend) = split_slots(&self.topo);
            let (a, b) = spring_halves(&self.topo.springs);
            let (a, b) = (a.to_vec(), b.to_vec());
            let interior = interior_block(&self.topo, self.variant.table);
            self.write(Buf::Slots, bytemuck::cast_slice(&strain))?;
            self.write(Buf::BendSlots, bytemuck::cast_slice(&bend))?;
            self.write(Buf::Springs, bytemuck::cast_slice(&a))?;
            self.write(Buf::SpringsB, bytemuck::cast_slice(&b))?;
            self.write(Buf::Interior, bytemuck::bytes_of(&interior))?;
        }
        // Specialised kernels follow what the parameters use (Coulomb's coefficients).
        let uses = uses_of(&self.variant, &self.scene, &params);
        let integration = Integration::of(&params);
        let step = specialised(recipe_for(&self.variant, params.strain_iterations, integration, &self.topo), uses);
        let group = recipe_group(&self.variant, &params, &self.topo, self.options, &self.scene)?;
        let end = specialised(frame_end(&self.variant, integration), uses);
        let (step, end) = crate::worlds::in_worlds(step, end, self.worlds.len())?;
        for k in kernels_of(&step).into_iter().chain(kernels_of(&end)) {
            self.build(k)?;
        }
        self.engine.check("building the integrator's kernels")?;
        self.recipe = step;
        self.frame_end = end;
        self.substeps_per_recording = group;
        self.params = params;
        self.worlds = worlds;
        Ok(())
    }

    /// The engine (the API's device and buffers).
    pub fn engine(&self) -> &E {
        &self.engine
    }

    /// Blocks until everything submitted is done (then fails with what the driver
    /// reported, if anything).
    pub fn finish(&mut self) -> Result<(), SolverError> {
        self.engine.finish()?;
        self.engine.check("finishing the frame")
    }

    /// Fails with what the driver (or validation layer) reported since the last check.
    pub fn check(&mut self, what: &'static str) -> Result<(), SolverError> {
        self.engine.check(what)
    }

    /// The buffer bound as `buf` now (the position pair by the current parity).
    fn id(&self, buf: Buf) -> Option<BufferId> {
        match buf {
            Buf::Pos => Some(self.pos[self.current_pos]),
            Buf::PosOut => Some(self.pos[1 - self.current_pos]),
            b => self.ids.iter().find(|(x, _)| *x == b).map(|(_, id)| *id),
        }
    }

    fn must(&self, buf: Buf) -> Result<BufferId, SolverError> {
        self.id(buf).ok_or_else(|| SolverError::Invalid(format!("no buffer {}", buf.name())))
    }

    /// The connectivity and spring constants it runs.
    pub fn topology(&self) -> &ClothTopology {
        &self.topo
    }

    /// The renderer's vertex buffers, positions and normals: the simulation's own
    /// (`draw=shared`), or the copies made at the end of every frame (`draw=copy`).
    pub fn vertex_buffers(&self) -> (&E::Buffer, &E::Buffer) {
        match self.draw {
            Some([pos, normal]) => (self.engine.buffer(pos), self.engine.buffer(normal)),
            None => (
                self.engine.buffer(self.pos[self.current_pos]),
                self.engine.buffer(self.id(Buf::Normal).expect("normal buffer")),
            ),
        }
    }

    /// Records the copies of the positions and normals into the renderer's buffers
    /// (`draw=copy`), after the barrier they need.
    fn record_draw_copy(&mut self) -> Result<(), SolverError> {
        let Some([pos, normal]) = self.draw else { return Ok(()) };
        let (from_pos, from_normal) = (self.pos[self.current_pos], self.must(Buf::Normal)?);
        let bytes = 16 * self.topo.num_particles() as u64;
        let reads = bits(Buf::Pos, self.current_pos) | bits(Buf::Normal, self.current_pos);
        if self.hazards.conflicts(reads, 0) {
            self.barrier(false);
        }
        self.hazards.add(reads, 0);
        self.engine.copy(from_pos, pos, bytes);
        self.engine.copy(from_normal, normal, bytes);
        Ok(())
    }

    /// The adapter, in one line.
    pub fn adapter(&self) -> String {
        self.engine.info().adapter.clone()
    }

    /// The variant it runs (the preset fitted to the adapter, the switches applied).
    pub fn variant(&self) -> Variant {
        self.variant
    }

    /// What the adapter offers that variants use.
    pub fn caps(&self) -> Caps {
        self.caps
    }

    /// The options it was built with.
    pub fn options(&self) -> SolverOptions {
        self.options
    }

    /// The commands of one substep (statistics included).
    pub fn commands(&self) -> Vec<Command> {
        let mut r = self.recipe.clone();
        r.extend(stats_commands(self.options.stats, self.caps));
        r
    }

    /// The commands that run once after a frame's last substep (`normals=frame`: the
    /// normals; usually none).
    pub fn frame_end(&self) -> &[Command] {
        &self.frame_end
    }

    /// The kernels one substep dispatches, in order (statistics included), then those the
    /// frame's end adds.
    pub fn recipe_kernels(&self) -> Vec<KernelRef> {
        kernels_of(&[self.commands(), self.frame_end.clone()].concat())
    }

    /// Pipeline barriers recorded in the last frame (none on an API that places its own).
    pub fn barriers_last_frame(&self) -> usize {
        self.barriers
    }

    /// Records the colliders at the current time (`Scene::colliders_at`) into the buffers
    /// the recipe reads them from, between barriers: after the last substep's reads,
    /// before the next one's (moving colliders only; still ones stay as uploaded).
    fn record_colliders(&mut self) -> Result<(), SolverError> {
        let (mut spheres, mut boxes) = (Vec::new(), Vec::new());
        self.scene.colliders_at(self.time, &mut spheres, &mut boxes);
        // Both homes: with colliders=uniform the kernels without a `_cu` flavor (the
        // strain passes' collide, VBD's contacts) still read the storage buffers.
        let mut homes = vec![(Buf::Spheres, Buf::Boxes)];
        if self.variant.colliders == Colliders::Uniform {
            homes.push((Buf::SpheresUniform, Buf::BoxesUniform));
        }
        self.barrier(false);
        for (sb, bb) in homes {
            if !spheres.is_empty() {
                let id = self.must(sb)?;
                self.engine.record_write(id, bytemuck::cast_slice(&spheres))?;
            }
            if !boxes.is_empty() {
                let id = self.must(bb)?;
                self.engine.record_write(id, bytemuck::cast_slice(&boxes))?;
            }
        }
        // The bodies' heads and the rods lead the shapes buffer.
        if !self.scene.bodies.is_empty() || !self.scene.rods.is_empty() {
            let id = self.must(Buf::Shapes)?;
            self.engine.record_write(id, bytemuck::cast_slice(&self.scene.shapes_at(self.time)))?;
        }
        self.barrier(false);
        Ok(())
    }

    /// Records a barrier and notes it.
    fn barrier(&mut self, after_all: bool) {
        self.engine.barrier(after_all);
        self.hazards.clear();
        self.barriers += 1;
    }

    /// Records `commands` of substep `substep` (each after the barrier it needs),
    /// timestamps from query `*q` on while timing and there is room.
    fn record(&mut self, commands: &[Command], substep: u32, q: &mut u32, labels: &mut Vec<&'static str>) {
        // The substep's first block of pin poses (a batch's: a block per world).
        let substep_bytes = (substep * self.worlds.len() as u32).to_le_bytes();
        let timestamps = self.time_kernels && self.engine.info().timestamps;
        for c in commands {
            // Only the barriers the data needs (see recipe::Hazards); a swap flips `cur`.
            let mut cur = self.current_pos;
            if self.hazards.command(c, &mut cur) {
                self.engine.barrier(false);
                self.barriers += 1;
            }
            self.current_pos = cur;
            let k = match c {
                Command::Clear(buf) => {
                    if let Some(id) = self.id(*buf) {
                        self.engine.clear(id);
                    }
                    continue;
                }
                Command::Swap => continue,
                Command::Dispatch(k) => (*k, k.def.count.of(&self.topo), [0; 2]),
                Command::Range { kernel, first, count } => (*kernel, *count, [*first, *count]),
            };
            let (k, count, range) = k;
            let range_bytes: &[u8] = bytemuck::cast_slice(&range);
            let immediates: &[u8] = if k.step_immediates() {
                self.step_params.gpu_bytes()
            } else if k.def.immediates == Immediates::Substep {
                &substep_bytes
            } else if k.def.immediates == Immediates::Range {
                range_bytes
            } else {
                &[]
            };
            let timed = timestamps && *q + 2 <= MAX_QUERIES;
            self.engine.dispatch(&Dispatch {
                kernel: k,
                parity: self.current_pos,
                groups: {
                    let (x, y) = groups(count);
                    (x, y, self.worlds.len() as u32)
                },
                immediates,
                timestamps: timed.then_some(*q),
            });
            if timed {
                *q += 2;
                labels.push(k.def.label);
            }
        }
    }

    /// Writes `bytes` into `buf` now (everything recorded later must wait for it).
    fn write(&mut self, buf: Buf, bytes: &[u8]) -> Result<(), SolverError> {
        self.hazards.dirty();
        let id = self.must(buf)?;
        self.engine.write(id, bytes)
    }

    fn read(&mut self, buf: Buf) -> Result<Vec<V4>, SolverError> {
        let id = self.must(buf)?;
        let bytes = self.engine.read(id)?;
        Ok(bytes.chunks_exact(16).map(bytemuck::pod_read_unaligned::<V4>).collect())
    }

    /// Uploads `bufs` and `sp`, runs `commands`, reads the buffers back (see
    /// [`KernelRunner::run_commands`]). The next frame uploads the solver's own constants.
    fn run_host(&mut self, commands: &[Command], sp: &StepParams, bufs: &mut HostBuffers) -> Result<(), SolverError> {
        bufs.check(&self.topo, sp)?;
        for k in dispatches(commands) {
            self.build(k)?;
        }
        self.write(Buf::Params, sp.gpu_bytes())?;
        self.write(Buf::ParamsStorage, sp.gpu_bytes())?;
        self.write(Buf::Contact, bytemuck::bytes_of(&sp.contact))?;
        self.step_params = *sp;
        let moved = host_buffers(commands);
        if moved.contains(&Buf::TriInts) {
            if !self.tri_buffers {
                return Err(SolverError::Unsupported(
                    "the contact between triangles' kernels on a solver built without its buffers".into(),
                ));
            }
            bufs.tri_sized(clothlab_cpu::tri_contact::TriLayout::of(&self.topo));
        }
        if moved.contains(&Buf::Adjoint) {
            if !has_adjoint(&self.topo) || self.worlds.len() > 1 {
                return Err(SolverError::Unsupported(format!(
                    "the adjoint's kernels run on a single run's cloth of at most {TRI_BUFFERS_ALWAYS} particles"
                )));
            }
            bufs.adjoint_sized(self.topo.num_particles());
        }
        for &buf in &moved {
            if let Some(v) = bufs.get(buf) {
                self.write(buf, bytemuck::cast_slice(v))?;
            }
        }
        // The pin poses are an input only: uploaded, not read back; the commands run as
        // substep 0, so its block is all they read.
        let reads_poses = dispatches(commands).any(|k| k.def.reads.contains(&Buf::PinPoses));
        if reads_poses {
            let block = &bufs.pin_poses[..PinPose::V4S * MAX_PIN_GROUPS];
            self.write(Buf::PinPoses, bytemuck::cast_slice(block))?;
        }
        let was = std::mem::replace(&mut self.time_kernels, false);
        let recorded = self.engine.begin(0, 0).map(|_| self.record(commands, 0, &mut 0, &mut Vec::new()));
        self.time_kernels = was;
        recorded?;
        self.engine.submit(true)?;
        self.engine.wait(0)?;
        self.engine.check("running commands")?;
        for &buf in &moved {
            let v = self.read(buf)?;
            if let Some(dst) = bufs.get_mut(buf) {
                *dst = v;
            }
        }
        Ok(())
    }
}

/// What `variant`'s kernels keep of the collider walk for `scene` and `params`: the
/// scene's uses with `specialize=on`, everything otherwise.
fn uses_of(variant: &Variant, scene: &Scene, params: &SimParams) -> Uses {
    match variant.specialize {
        Specialize::On => Uses::of(scene, params),
        Specialize::Off => Uses::ALL,
    }
}

/// `commands` with every kernel specialised to `uses`.
fn specialised(commands: Vec<Command>, uses: Uses) -> Vec<Command> {
    if uses == Uses::ALL {
        return commands;
    }
    commands
        .into_iter()
        .map(|c| match c {
            Command::Dispatch(k) => Command::Dispatch(k.with_uses(uses)),
            Command::Range { kernel, first, count } => Command::Range { kernel: kernel.with_uses(uses), first, count },
            c => c,
        })
        .collect()
}

/// The uniform block of the regular grid's spring constants, switched off when the table
/// is to be read from storage or an image everywhere.
fn interior_block(topo: &ClothTopology, table: Table) -> GridSpringConstants {
    let mut interior = GridSpringConstants::new(topo);
    if table != Table::Uniform {
        interior.enabled = 0;
    }
    interior
}

impl<E: Engine> KernelRunner for GpuSolver<E> {
    fn kernels(&self) -> Vec<KernelRef> {
        let mut v = self.engine.kernels();
        v.extend(self.offered.iter().copied());
        v.sort_by_key(|k| k.shader_name());
        v.dedup();
        // The adjoint's kernels only where it has their planes.
        if !has_adjoint(&self.topo) || self.worlds.len() > 1 {
            v.retain(|k| !crate::kernels::ADJOINT_KERNELS.contains(&k.def));
        }
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
        self.engine.info().adapter.clone()
    }

    fn add_kernel(&mut self, kernel: KernelRef) -> Result<(), SolverError> {
        self.build(kernel)?;
        self.engine.check("building a kernel")
    }
}

impl<E: Engine> Solver for GpuSolver<E> {
    fn name(&self) -> &str {
        &self.name
    }

    /// Every world's group (a batch's one by one: [`Batch::set_world_pin_motion`]).
    fn set_pin_motion(&mut self, group: usize, motion: clothlab_core::motion::Motion) -> Result<(), SolverError> {
        clothlab_core::pins::set_scripted(&mut self.scene.pins, group, motion.clone())?;
        for pins in &mut self.world_pins {
            clothlab_core::pins::set_scripted(pins, group, motion.clone())?;
        }
        Ok(())
    }

    fn scene(&self) -> &Scene {
        &self.scene
    }

    fn params(&self) -> &SimParams {
        &self.params
    }

    /// Every world's parameters (a batch's one by one: [`Batch::set_world_params`]).
    fn set_params(&mut self, params: SimParams) -> Result<(), SolverError> {
        self.apply_params(vec![params; self.worlds.len()])
    }

    fn set_grab(&mut self, grab: Option<Grab>) {
        self.grab = Grab::checked(grab, self.topo.num_particles());
    }

    fn step_frame(&mut self) -> Result<(), SolverError> {
        let t0 = Instant::now();
        self.step_params = StepParams::new(&self.params, &self.scene, self.grab);
        self.step_params.tile_substeps = self.substeps_per_recording;
        if self.worlds.len() > 1 && self.tri_buffers {
            self.step_params.contact.tri_world_words =
                clothlab_cpu::tri_contact::TriLayout::of(&self.topo).words() as u32;
        }
        // A batch's worlds' constants (world 0 holds the grab), every frame.
        let world_bytes: Option<Vec<u8>> = (self.worlds.len() > 1).then(|| {
            self.worlds
                .iter()
                .enumerate()
                .flat_map(|(k, p)| {
                    let mut sp = StepParams::new(p, &self.scene, if k == 0 { self.grab } else { None });
                    sp.tile_substeps = self.substeps_per_recording;
                    sp.gpu_bytes().to_vec()
                })
                .collect()
        });
        let commands = self.commands();
        let stats = self.options.stats != StatsMode::Off;
        let substeps = self.params.substeps;
        // One submission for the frame, or one per substep submitted without waiting in
        // between (the wait on the last covers all of them).
        let submissions = match self.variant.submit {
            Submit::Frame => 1,
            Submit::Substep => substeps,
        };
        let per_submission = substeps / submissions;
        let end = self.frame_end.clone();
        let (per_substep, per_end) = (dispatches(&commands).count(), dispatches(&end).count());
        let max_q = if self.time_kernels && self.engine.info().timestamps {
            (2 * (substeps as usize * per_substep + per_end)).min(MAX_QUERIES as usize) as u32
        } else {
            0
        };
        let (mut q, mut labels) = (0, Vec::new());
        let (mut record_ns, mut submit_ns) = (0.0, 0.0);
        let (params, contact, params_storage, stats_max, stats_energy) = (
            self.must(Buf::Params)?,
            self.must(Buf::Contact)?,
            self.must(Buf::ParamsStorage)?,
            self.must(Buf::StatsMax)?,
            self.must(Buf::StatsEnergy)?,
        );
        let (tri_ints, contact_on) = (self.must(Buf::TriInts)?, self.params.self_collision.triangles());
        self.barriers = 0;
        for k in 0..submissions {
            let t_record = Instant::now();
            self.engine.begin(k as usize, if k == 0 { max_q } else { 0 })?;
            if k == 0 {
                // The frame's constants are recorded into the frame itself (Vulkan: a copy
                // before the first dispatch; wgpu: a queue write), not a submission of
                // their own.
                self.engine.record_write(params, self.step_params.gpu_bytes())?;
                self.engine.record_write(contact, bytemuck::bytes_of(&self.step_params.contact))?;
                // The frame's poses of the moving pins, every substep's block at once.
                if !self.topo.pins.slots.is_empty() {
                    let poses = self.frame_poses(substeps);
                    let id = self.must(Buf::PinPoses)?;
                    self.engine.record_write(id, bytemuck::cast_slice(&poses))?;
                }
                // The storage copy only for a recipe that reads it (kernel checks write both);
                // a batch's `_w` kernels read every world's there.
                if let Some(bytes) = &world_bytes {
                    self.engine.record_write(params_storage, bytes)?;
                } else if self.variant.constants == Constants::Storage {
                    self.engine.record_write(params_storage, self.step_params.gpu_bytes())?;
                }
                let mut written = res::PARAMS;
                if stats {
                    self.engine.clear(stats_max);
                    self.engine.clear(stats_energy);
                    written |= res::STATS;
                }
                // One barrier after all earlier work (the renderer may still have been
                // reading the positions as vertices) and the writes above.
                self.hazards.add(0, written);
                self.barrier(true);
            }
            // With temporal blocking one recording advances `group` substeps.
            let group = self.substeps_per_recording;
            for s in (0..per_submission).map(|s| k * per_submission + s).filter(|s| s.is_multiple_of(group)) {
                if self.scene.moves() {
                    self.record_colliders()?;
                }
                self.time += self.params.dt() as f64 * group as f64;
                for t in &mut self.times {
                    *t += self.params.dt() as f64 * group as f64;
                }
                self.record(&commands, s, &mut q, &mut labels);
            }
            let last = k + 1 == submissions;
            if last {
                self.record(&end, substeps - 1, &mut q, &mut labels);
                self.record_draw_copy()?;
            }
            if last && stats {
                if self.hazards.conflicts(res::STATS, 0) {
                    self.barrier(false);
                }
                self.hazards.add(res::STATS, 0);
                self.engine.readback(stats_max, 4 * substeps as u64)?;
                self.engine.readback(stats_energy, 4 * substeps as u64)?;
            }
            if last && contact_on {
                // The contact's scalars (the head of its integers): its last substep's counts.
                if self.hazards.conflicts(res::TRI, 0) {
                    self.barrier(false);
                }
                self.hazards.add(res::TRI, 0);
                self.engine.readback(tri_ints, 4 * clothlab_cpu::tri_contact::at::WORDS as u64)?;
            }
            record_ns += t_record.elapsed().as_nanos() as f64;
            let t_submit = Instant::now();
            self.engine.submit(last)?;
            submit_ns += t_submit.elapsed().as_nanos() as f64;
        }
        let finished = self.engine.wait(q)?;
        self.engine.check("simulating a frame")?;
        let mut readbacks = finished.readbacks.iter();
        if stats && let (Some(max), Some(energy)) = (readbacks.next(), readbacks.next()) {
            let word = |b: &[u8], k: usize| f32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]]);
            self.stats = (0..substeps as usize)
                .map(|k| SubstepStats { max_strain: word(max, k), kinetic_energy: word(energy, k) })
                .collect();
        }
        self.contact = match readbacks.next() {
            Some(b) if contact_on => {
                let words: Vec<u32> = b.chunks_exact(4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]])).collect();
                self.searches += substeps as u64;
                Some(clothlab_core::solver::ContactStats {
                    searches: self.searches,
                    ..clothlab_cpu::tri_contact::stats(&words)
                })
            }
            _ => None,
        };
        if self.time_kernels {
            self.timer.record(CPU_RECORD, record_ns);
            self.timer.record(CPU_SUBMIT, submit_ns);
            let frame = if q > 0 {
                let period = self.engine.info().timestamp_period_ns;
                record_times(
                    &mut self.timer,
                    &labels,
                    &finished.ticks,
                    period,
                    per_substep,
                    per_end,
                    (substeps, self.substeps_per_recording),
                )
            } else {
                self.engine.finish()?;
                t0.elapsed().as_nanos() as f64
            };
            self.timer.record(FRAME, frame);
        }
        Ok(())
    }

    /// World 0's state (a batch's other worlds: [`Batch::world_state`]).
    fn state(&mut self) -> Result<ClothState, SolverError> {
        self.world_state(0)
    }

    /// World 0's (every world's: [`Batch::fields`]).
    fn field(&mut self, field: clothlab_core::StateField) -> Result<Vec<clothlab_core::grid::V4>, SolverError> {
        let mut v = self.fields(field)?;
        v.truncate(self.topo.num_particles());
        Ok(v)
    }

    fn time(&self) -> f64 {
        self.time
    }

    /// The clock and every world's time.
    fn set_time(&mut self, t: f64) -> Result<(), SolverError> {
        self.time = clothlab_core::solver::checked_time(t)?;
        self.times.iter_mut().for_each(|w| *w = t);
        Ok(())
    }

    /// World 0's state (a batch's other worlds: [`Batch::set_world_state`]).
    fn set_state(&mut self, state: &ClothState) -> Result<(), SolverError> {
        self.set_world_state(0, state)
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

    fn contact_stats(&self) -> Option<clothlab_core::solver::ContactStats> {
        self.contact
    }

    fn substep_stats(&self) -> Vec<SubstepStats> {
        self.stats.clone()
    }
}

/// A batch of worlds in one solver ([`GpuSolver::new_worlds`], [`crate::worlds`]): what
/// reads and writes one world, or every world at once. A single run is a batch of one.
pub trait Batch {
    /// How many worlds.
    fn envs(&self) -> usize;
    /// Each world's parameters.
    fn world_params(&self) -> &[SimParams];
    /// Sets each world's parameters (one a world), checked first: nothing changes where
    /// one is refused.
    fn set_world_params(&mut self, worlds: Vec<SimParams>) -> Result<(), SolverError>;
    /// World `k`'s state.
    fn world_state(&mut self, k: usize) -> Result<ClothState, SolverError>;
    /// Sets world `k`'s state.
    fn set_world_state(&mut self, k: usize, state: &ClothState) -> Result<(), SolverError>;
    /// A field of every world, world after world.
    fn fields(&mut self, field: clothlab_core::StateField) -> Result<Vec<V4>, SolverError>;
    /// Every world's state, each buffer read once.
    fn states(&mut self) -> Result<Vec<ClothState>, SolverError>;
    /// Sets every world's state (one a world, each checked first: nothing changes where
    /// one is refused), each buffer written once.
    fn set_states(&mut self, states: &[ClothState]) -> Result<(), SolverError>;
    /// World `k`'s simulated time, s.
    fn world_time(&self, k: usize) -> f64;
    /// Sets world `k`'s time; refused in a scene whose colliders or pins move (its worlds
    /// share their clock) unless it is every world's.
    fn set_world_time(&mut self, k: usize, t: f64) -> Result<(), SolverError>;
    /// World `k`'s pin groups (a script's motions in its own).
    fn world_pins(&self, k: usize) -> Result<&[clothlab_core::PinGroup], SolverError>;
    /// Sets the motion of world `k`'s scripted pin group `group`
    /// ([`Solver::set_pin_motion`] for one world).
    fn set_world_pin_motion(
        &mut self,
        k: usize,
        group: usize,
        motion: clothlab_core::motion::Motion,
    ) -> Result<(), SolverError>;
}

impl<E: Engine> GpuSolver<E> {
    /// The frame's poses of the moving pins, a block of MAX_PIN_GROUPS per substep; a
    /// batch's per substep a block per world, world after world (each world's groups,
    /// from the shared clock).
    fn frame_poses(&self, substeps: u32) -> Vec<PinPose> {
        let dt = self.params.dt() as f64;
        let poses = |pins: &[clothlab_core::PinGroup]| {
            clothlab_core::pins::frame_poses(
                pins,
                &self.topo.pins.pivots,
                self.params.integrator,
                self.time,
                dt,
                substeps,
            )
        };
        if self.world_pins.is_empty() {
            return poses(&self.scene.pins);
        }
        let each: Vec<Vec<PinPose>> = self.world_pins.iter().map(|p| poses(p)).collect();
        (0..substeps as usize)
            .flat_map(|s| {
                each.iter().flat_map(move |w| w[s * MAX_PIN_GROUPS..(s + 1) * MAX_PIN_GROUPS].iter().copied())
            })
            .collect()
    }

    /// World `k` checked against the batch.
    fn check_world(&self, k: usize) -> Result<(), SolverError> {
        if k >= self.worlds.len() {
            return Err(SolverError::Invalid(format!(
                "world {k}: the batch has {} worlds (0 ..= {})",
                self.worlds.len(),
                self.worlds.len() - 1
            )));
        }
        Ok(())
    }

    /// The buffer bound as `buf`, world `k`'s rows replaced by `rows`.
    fn write_world(&mut self, buf: Buf, k: usize, rows: &[V4]) -> Result<(), SolverError> {
        if self.worlds.len() == 1 {
            return self.write(buf, bytemuck::cast_slice(rows));
        }
        let np = self.topo.num_particles();
        let mut all = self.read(buf)?;
        all[k * np..(k + 1) * np].copy_from_slice(rows);
        self.write(buf, bytemuck::cast_slice(&all))
    }
}

impl<E: Engine> Batch for GpuSolver<E> {
    fn envs(&self) -> usize {
        self.worlds.len()
    }

    fn world_params(&self) -> &[SimParams] {
        &self.worlds
    }

    fn set_world_params(&mut self, worlds: Vec<SimParams>) -> Result<(), SolverError> {
        self.apply_params(worlds)
    }

    fn world_state(&mut self, k: usize) -> Result<ClothState, SolverError> {
        self.check_world(k)?;
        let (n, np) = (self.topo.n, self.topo.num_particles());
        let mut one = |buf: Buf| -> Result<Vec<V4>, SolverError> { Ok(self.read(buf)?[k * np..(k + 1) * np].to_vec()) };
        Ok(ClothState {
            n,
            pos: one(Buf::Pos)?,
            vel: one(Buf::Vel)?,
            force: one(Buf::Force)?,
            normal: one(Buf::Normal)?,
        })
    }

    fn set_world_state(&mut self, k: usize, state: &ClothState) -> Result<(), SolverError> {
        self.check_world(k)?;
        state.check(&self.topo)?;
        self.write_world(Buf::Pos, k, &state.pos)?;
        self.write_world(Buf::Vel, k, &state.vel)?;
        self.write_world(Buf::Force, k, &state.force)?;
        self.write_world(Buf::Normal, k, &state.normal)?;
        // The renderer's copies hold world 0.
        if let (0, Some([pos, normal])) = (k, self.draw) {
            self.engine.write(pos, bytemuck::cast_slice(&state.pos))?;
            self.engine.write(normal, bytemuck::cast_slice(&state.normal))?;
        }
        Ok(())
    }

    fn fields(&mut self, field: clothlab_core::StateField) -> Result<Vec<V4>, SolverError> {
        use clothlab_core::StateField;
        self.read(match field {
            StateField::Pos => Buf::Pos,
            StateField::Vel => Buf::Vel,
            StateField::Force => Buf::Force,
            StateField::Normal => Buf::Normal,
        })
    }

    fn states(&mut self) -> Result<Vec<ClothState>, SolverError> {
        let (n, np) = (self.topo.n, self.topo.num_particles().max(1));
        let [pos, vel, force, normal] = [Buf::Pos, Buf::Vel, Buf::Force, Buf::Normal].map(|b| self.read(b));
        let (pos, vel, force, normal) = (pos?, vel?, force?, normal?);
        Ok((0..self.worlds.len())
            .map(|k| {
                let rows = |v: &[V4]| v[k * np..(k + 1) * np].to_vec();
                ClothState { n, pos: rows(&pos), vel: rows(&vel), force: rows(&force), normal: rows(&normal) }
            })
            .collect())
    }

    fn set_states(&mut self, states: &[ClothState]) -> Result<(), SolverError> {
        if states.len() != self.worlds.len() {
            return Err(SolverError::Invalid(format!("{} states for {} worlds", states.len(), self.worlds.len())));
        }
        for (k, st) in states.iter().enumerate() {
            st.check(&self.topo).map_err(|e| SolverError::Invalid(format!("world {k}: {e}")))?;
        }
        let all =
            |f: fn(&ClothState) -> &Vec<V4>| states.iter().flat_map(|st| f(st).iter().copied()).collect::<Vec<V4>>();
        let (pos, vel, force, normal) = (all(|s| &s.pos), all(|s| &s.vel), all(|s| &s.force), all(|s| &s.normal));
        self.write(Buf::Pos, bytemuck::cast_slice(&pos))?;
        self.write(Buf::Vel, bytemuck::cast_slice(&vel))?;
        self.write(Buf::Force, bytemuck::cast_slice(&force))?;
        self.write(Buf::Normal, bytemuck::cast_slice(&normal))?;
        if let Some([p, nrm]) = self.draw {
            self.engine.write(p, bytemuck::cast_slice(&states[0].pos))?;
            self.engine.write(nrm, bytemuck::cast_slice(&states[0].normal))?;
        }
        Ok(())
    }

    fn world_time(&self, k: usize) -> f64 {
        self.times.get(k).copied().unwrap_or(f64::NAN)
    }

    fn set_world_time(&mut self, k: usize, t: f64) -> Result<(), SolverError> {
        self.check_world(k)?;
        let t = clothlab_core::solver::checked_time(t)?;
        if self.scene.moves() && self.times.iter().enumerate().any(|(j, &w)| j != k && w != t) {
            return Err(SolverError::Unsupported(format!(
                "world {k}: a GPU batch's worlds share the clock of the scene's moving colliders and pins: its time cannot differ from the others'"
            )));
        }
        self.times[k] = t;
        if k == 0 {
            self.time = t;
        }
        Ok(())
    }

    fn world_pins(&self, k: usize) -> Result<&[clothlab_core::PinGroup], SolverError> {
        self.check_world(k)?;
        Ok(if self.world_pins.is_empty() { &self.scene.pins } else { &self.world_pins[k] })
    }

    fn set_world_pin_motion(
        &mut self,
        k: usize,
        group: usize,
        motion: clothlab_core::motion::Motion,
    ) -> Result<(), SolverError> {
        self.check_world(k)?;
        if self.world_pins.is_empty() {
            return self.set_pin_motion(group, motion);
        }
        clothlab_core::pins::set_scripted(&mut self.world_pins[k], group, motion.clone())?;
        if k == 0 {
            clothlab_core::pins::set_scripted(&mut self.scene.pins, group, motion)?;
        }
        Ok(())
    }
}
