//! The CPU engine: runs any commands through the kernels' twins, on [`HostBuffers`].
//! It is the reference the GPU backends are checked against kernel by kernel, and the
//! CPU half of `clothlab validate --bisect`. The fast CPU solvers (`cpu`, `cpu-par`: SIMD
//! rows, fused sweeps) are a separate path, tested to give its bits.

use std::time::Instant;

use clothlab_core::build;
use clothlab_core::grid::{ClothState, ClothTopology, Grab, V4};
use clothlab_core::layout::Buf;
use clothlab_core::scene::Scene;
use clothlab_core::step_params::StepParams;
use clothlab_core::timing::{FRAME, KernelTimings, SUBSTEP, TimingRecorder};
use clothlab_core::{SimParams, Solver, SolverError};
use clothlab_cpu::ColliderSet;
use clothlab_cpu::{self as twins, Exec};

use crate::kernels::{HostBuffers, KernelRef, TwinArgs};
use crate::recipe::KernelRunner;
use crate::recipe::{Command, Integration, Variant, dispatch_substeps, frame_end, kernels_of, recipe_for};

/// Runs commands through the twins.
#[derive(Debug, Clone)]
pub struct CpuEngine {
    exec: Exec,
    scene: Scene,
    topo: ClothTopology,
    /// The colliders the twins see: the scene's at the time of [`CpuEngine::move_colliders`].
    colliders: ColliderSet,
}

impl CpuEngine {
    /// An engine for the cloth of `scene` with connectivity `topo`.
    pub fn new(exec: Exec, scene: Scene, topo: ClothTopology) -> Self {
        let colliders = ColliderSet::new(&scene);
        Self { exec, scene, topo, colliders }
    }

    /// Puts the colliders where their motions have them at time `t`, s (what a GPU solver
    /// writes before each substep).
    pub fn move_colliders(&mut self, t: f64) {
        self.colliders.move_to(&self.scene, t);
    }

    /// The connectivity and spring tables.
    pub fn topology(&self) -> &ClothTopology {
        &self.topo
    }

    /// Replaces the spring constants (after a parameter change).
    pub fn set_spring_constants(&mut self, params: &SimParams) {
        self.topo.set_spring_constants(params);
    }

    /// Runs one command of substep `substep` on `bufs`.
    pub fn command(&self, command: &Command, p: &StepParams, substep: u32, bufs: &mut HostBuffers) {
        match command {
            Command::Dispatch(k) => (k.def.twin)(&self.args(p, substep), bufs),
            Command::Range { kernel, first, count } => {
                let args = TwinArgs { range: (*first, *count), ..self.args(p, substep) };
                (kernel.def.twin)(&args, bufs)
            }
            Command::Clear(buf) => {
                if let Some(v) = bufs.get_mut(*buf) {
                    v.iter_mut().for_each(|x| *x = [0.0; 4]);
                } else if matches!(buf, Buf::StatsMax | Buf::StatsEnergy) {
                    bufs.stats.clear();
                }
            }
            Command::Swap => std::mem::swap(&mut bufs.pos, &mut bufs.pos_out),
        }
    }

    /// Runs `commands` of substep `substep` on `bufs`.
    pub fn run(&self, commands: &[Command], p: &StepParams, substep: u32, bufs: &mut HostBuffers) {
        for c in commands {
            self.command(c, p, substep, bufs);
        }
    }

    /// What the twins see besides the buffers.
    pub fn args<'a>(&'a self, p: &'a StepParams, substep: u32) -> TwinArgs<'a> {
        TwinArgs { exec: self.exec, p, topo: &self.topo, colliders: self.colliders.view(), substep, range: (0, 0) }
    }

    /// The buffers of `state`, with its face normals computed.
    pub fn buffers(&self, state: &ClothState) -> HostBuffers {
        let mut faces = vec![[0.0f32; 4]; self.topo.triangles.len()];
        twins::tri_normals(self.exec, &self.topo.triangles, &state.pos, &mut faces);
        HostBuffers::new(state, faces)
    }
}

/// Every kernel of the registry, in every flavor the caps allow, runs on the CPU engine.
impl KernelRunner for CpuEngine {
    fn kernels(&self) -> Vec<KernelRef> {
        crate::kernels::ALL.iter().flat_map(|d| d.flavors()).collect()
    }

    fn run_commands(
        &mut self,
        commands: &[Command],
        p: &StepParams,
        bufs: &mut HostBuffers,
    ) -> Result<(), SolverError> {
        self.run(commands, p, 0, bufs);
        Ok(())
    }

    fn adapter(&self) -> String {
        "the CPU engine (twins)".into()
    }

    /// Any kernel runs: its twin is in its row.
    fn add_kernel(&mut self, _kernel: KernelRef) -> Result<(), SolverError> {
        Ok(())
    }
}

/// A [`Solver`] that runs a variant's recipe on the [`CpuEngine`]: slow (one twin after
/// another, no SIMD), but exactly the commands a GPU backend records.
pub struct RecipeSolver {
    engine: CpuEngine,
    name: String,
    variant: Variant,
    params: SimParams,
    grab: Option<Grab>,
    bufs: HostBuffers,
    commands: Vec<Command>,
    /// What runs once after a frame's last substep.
    end: Vec<Command>,
    timer: TimingRecorder,
    /// Substeps one run of `commands` advances (`temporal=on`; 1 otherwise).
    group: u32,
    /// Simulated time, s.
    time: f64,
}

impl RecipeSolver {
    /// The cloth of `scene`, stepped by `variant`'s recipe (where constants, tables and
    /// colliders live and which atomics add change only which GPU shader runs, not the
    /// twin).
    pub fn new(exec: Exec, variant: Variant, scene: Scene, params: SimParams) -> Result<Self, SolverError> {
        let (state, topo) = build(&scene, &params)?;
        let engine = CpuEngine::new(exec, scene, topo);
        let sp = StepParams::new(&params, &engine.scene, None);
        let bufs = start_buffers(exec, &sp, &engine.topo, &state);
        let commands = recipe_for(&variant, params.strain_iterations, Integration::of(&params), &engine.topo);
        let end = frame_end(&variant, Integration::of(&params));
        let name = variant.solver_name("cpu-recipe");
        let group = dispatch_substeps(&variant, Integration::of(&params), params.strain_iterations, &engine.topo);
        if group > 1 && engine.scene.animated() {
            return Err(SolverError::Unsupported(
                "temporal=on advances several substeps with one pose of the colliders and pins: moving colliders or pins need temporal=off".into(),
            ));
        }
        Ok(Self {
            engine,
            name,
            variant,
            params,
            grab: None,
            bufs,
            commands,
            end,
            timer: TimingRecorder::default(),
            group,
            time: 0.0,
        })
    }

    /// The commands of one substep.
    pub fn commands(&self) -> &[Command] {
        &self.commands
    }

    /// What runs once after a frame's last substep.
    pub fn frame_end(&self) -> &[Command] {
        &self.end
    }

    /// The distinct kernels of a substep, then those of the frame's end.
    pub fn kernels(&self) -> Vec<KernelRef> {
        kernels_of(&[&self.commands[..], &self.end[..]].concat())
    }

    /// The engine.
    pub fn engine(&self) -> &CpuEngine {
        &self.engine
    }

    /// The face normals of the last substep.
    pub fn faces(&self) -> &[V4] {
        &self.bufs.faces
    }
}

impl Solver for RecipeSolver {
    fn name(&self) -> &str {
        &self.name
    }

    fn scene(&self) -> &Scene {
        &self.engine.scene
    }

    fn set_pin_motion(&mut self, group: usize, motion: clothlab_core::motion::Motion) -> Result<(), SolverError> {
        Ok(clothlab_core::pins::set_scripted(&mut self.engine.scene.pins, group, motion)?)
    }

    fn params(&self) -> &SimParams {
        &self.params
    }

    fn set_params(&mut self, params: SimParams) -> Result<(), SolverError> {
        self.engine.topo.validate_params(&params)?;
        self.engine.scene.check_motion_speed(params.dt())?;
        self.engine.set_spring_constants(&params);
        self.commands =
            recipe_for(&self.variant, params.strain_iterations, Integration::of(&params), &self.engine.topo);
        self.end = frame_end(&self.variant, Integration::of(&params));
        self.group =
            dispatch_substeps(&self.variant, Integration::of(&params), params.strain_iterations, &self.engine.topo);
        self.params = params;
        Ok(())
    }

    fn set_grab(&mut self, grab: Option<Grab>) {
        self.grab = Grab::checked(grab, self.engine.topo.num_particles());
    }

    fn step_frame(&mut self) -> Result<(), SolverError> {
        let t_frame = Instant::now();
        let mut p = StepParams::new(&self.params, &self.engine.scene, self.grab);
        p.tile_substeps = self.group;
        if !self.engine.topo.pins.slots.is_empty() {
            let scene = &self.engine.scene;
            let poses = clothlab_core::pins::frame_poses(
                &scene.pins,
                &self.engine.topo.pins.pivots,
                self.params.integrator,
                self.time,
                self.params.dt() as f64,
                self.params.substeps,
            );
            self.bufs.pin_poses = bytemuck::cast_slice(&poses).to_vec();
        }
        // With temporal blocking one run of the commands advances `group` substeps.
        for s in (0..self.params.substeps).filter(|s| s.is_multiple_of(self.group)) {
            let t_substep = Instant::now();
            if self.engine.scene.moves() {
                self.engine.move_colliders(self.time);
            }
            self.time += self.params.dt() as f64 * f64::from(self.group);
            for c in &self.commands {
                let t = Instant::now();
                self.engine.command(c, &p, s, &mut self.bufs);
                if let Some(k) = c.kernel() {
                    self.timer.record(k.def.label, t.elapsed().as_nanos() as f64 / f64::from(self.group));
                }
            }
            self.timer.record(SUBSTEP, t_substep.elapsed().as_nanos() as f64 / f64::from(self.group));
        }
        let last = self.params.substeps.saturating_sub(1);
        for c in &self.end {
            self.engine.command(c, &p, last, &mut self.bufs);
        }
        self.timer.record(FRAME, t_frame.elapsed().as_nanos() as f64);
        Ok(())
    }

    fn state(&mut self) -> Result<ClothState, SolverError> {
        Ok(self.bufs.state(self.engine.topo.n))
    }

    fn time(&self) -> f64 {
        self.time
    }

    fn set_time(&mut self, t: f64) -> Result<(), SolverError> {
        self.time = clothlab_core::solver::checked_time(t)?;
        Ok(())
    }

    fn set_state(&mut self, state: &ClothState) -> Result<(), SolverError> {
        state.check(&self.engine.topo)?;
        let faces = std::mem::take(&mut self.bufs.faces);
        self.bufs = HostBuffers::new(state, faces);
        Ok(())
    }

    fn timings(&self) -> KernelTimings {
        self.timer.table()
    }

    fn reset_timings(&mut self) {
        self.timer.clear();
    }
}

/// The buffers every solver starts from: `state` with its face normals, vertex normals
/// and wind force computed (with the step constants `p`).
pub fn start_buffers(exec: Exec, p: &StepParams, topo: &ClothTopology, state: &ClothState) -> HostBuffers {
    let mut faces = vec![[0.0f32; 4]; topo.triangles.len()];
    twins::tri_normals(exec, &topo.triangles, &state.pos, &mut faces);
    let mut b = HostBuffers::new(state, faces);
    twins::vertex_normals(exec, p, &topo.face_slots, &b.faces, &mut b.normal, &mut b.force);
    b
}
