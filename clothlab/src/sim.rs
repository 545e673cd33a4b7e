//! [`Sim`]: a scene running on a backend, as a library sees it.

use std::path::Path;

use anyhow::{Context, Result, bail};
use clothlab_core::grid::Grab;
use clothlab_core::params::Integrator;
use clothlab_core::{ClothState, ClothTopology, KernelTimings, RenderMode, Scene, SimParams, Solver, StateField, View};
use clothlab_cpu::{CpuSolver, Exec};
use clothlab_engine::Batch;
use rayon::prelude::*;

use crate::backend::{AnySolver, Backend, GpuSetup, Shared, make, make_worlds};
use crate::record::Recorder;
use crate::setup::{Physics, Setup, check_lists, split_world_sets, world_lists, world_params};

pub use clothlab_core::scene_file::MAX_ENVS;

/// Most particles a batch of worlds may hold in all (as one cloth of [`MAX_N`]²).
///
/// [`MAX_N`]: clothlab_core::scene::MAX_N
pub const MAX_BATCH_PARTICLES: usize = (clothlab_core::scene::MAX_N as usize).pow(2);

/// The grid's side when neither the options nor the scene file give one (as `clothlab sim`).
pub const DEFAULT_N: u32 = 100;

/// Most frames or substeps one call may ask for.
pub const MAX_STEPS: u64 = 100_000_000;

/// What [`Sim::open`] opens.
#[derive(Debug, Clone, Default)]
pub struct SimOptions {
    /// The backend (default: `cpu`).
    pub backend: Backend,
    /// The scene, the integrator and parameter overrides.
    pub physics: Physics,
    /// A grid's particles per side, over the scene's (default [`DEFAULT_N`] for the
    /// default scene); refused for a mesh.
    pub n: Option<u32>,
    /// A GPU backend's variant and statistics; refused for a CPU backend unless default.
    pub gpu: GpuSetup,
    /// Worlds: copies of the scene stepped together, each with its own state and
    /// parameters (default: the scene file's `envs`, else 1). More than one runs on the
    /// CPU backends for now.
    pub envs: Option<u32>,
    /// Record the run for gradients ([`Sim::backward`], docs/gradients.md): one world, on
    /// `cpu` or `cpu-par` for now; what has no adjoint yet is refused when opened.
    pub grad: bool,
}

/// One cloth's particles and triangles in a scene's arrays.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ClothRange {
    /// Its name in the scene: `cloth[k]`, and a mesh's file.
    pub label: String,
    /// Its first particle.
    pub first: u32,
    /// How many particles.
    pub count: u32,
    /// Its first triangle.
    pub first_triangle: u32,
    /// How many triangles.
    pub triangles: u32,
}

/// A scene simulated on one backend: step it, read and write its state, grab a particle,
/// change its parameters, draw it, record it.
///
/// ```no_run
/// let mut sim = clothlab::Sim::open(clothlab::SimOptions { n: Some(32), ..Default::default() })?;
/// sim.step(10)?;
/// let lowest = sim.positions()?.iter().map(|p| p[1]).fold(f32::INFINITY, f32::min);
/// println!("lowest point after {:.3} s: {lowest:.3} m", sim.time());
/// # Ok::<(), anyhow::Error>(())
/// ```
///
/// A batch of worlds (`envs` > 1) is the scene copied: world k's state and parameters are
/// its own, and it computes, bit for bit, what a single run of the scene with world k's
/// parameters computes. The state's arrays ([`Sim::positions`] and the like) hold every
/// world's particles, world after world; what reads one cloth (its state, a picture, a
/// recording) reads world 0. On the CPU each world is a solver of its own, the worlds
/// stepped on rayon's threads on `cpu-par` (a kernel costs no launch there, so a world
/// runs its substeps through without waiting for the others); on a GPU backend one solver
/// holds every world and dispatches each kernel once for all of them
/// (`clothlab_engine::worlds`: what its worlds share, what it refuses).
pub struct Sim {
    /// World 0 (a GPU batch: every world).
    solver: AnySolver,
    /// Worlds 1 and on (a batch on a CPU backend).
    worlds: Vec<CpuSolver>,
    backend: Backend,
    setup: Setup,
    /// The GPU variant it was opened with (what [`Sim::reset`] builds a GPU world with).
    gpu: GpuSetup,
    /// The recording for gradients ([`SimOptions::grad`]).
    grad: Option<Box<Grad>>,
}

/// A run recorded for gradients: the recording, what its model was built from, and the
/// state the last recorded frame ended with.
struct Grad {
    rec: clothlab_cpu::grad::Recording,
    params: SimParams,
    w: Vec<f32>,
    ended: Option<ClothState>,
}

impl SimOptions {
    /// World `k`'s single run: these options with one world, each value given a world —
    /// a list of `physics.set` or of the scene file's `[params]` — its k-th (what world k
    /// of the batch computes, bit for bit).
    pub fn world(&self, k: usize) -> Result<SimOptions> {
        let (common, per_world) = split_world_sets(&self.physics.set);
        let setup = Physics { set: common.clone(), ..self.physics.clone() }.setup(self.n, DEFAULT_N)?;
        let lists = world_lists(&setup, &self.physics.set, per_world);
        let envs = self.envs.or(setup.envs).unwrap_or(1) as usize;
        if k >= envs {
            bail!("world {k}: the batch has {envs} worlds (0 ..= {})", envs - 1);
        }
        check_lists(&lists, envs)?;
        let mut set = common;
        set.extend(lists.iter().map(|(name, values)| format!("{name}={}", values[k])));
        Ok(SimOptions { physics: Physics { set, ..self.physics.clone() }, envs: Some(1), ..self.clone() })
    }
}

impl Sim {
    /// Opens the scene of `opts` on its backend. Every argument is checked first; a GPU
    /// backend without an adapter is refused in one line.
    pub fn open(opts: SimOptions) -> Result<Sim> {
        let (common, per_world) = split_world_sets(&opts.physics.set);
        let physics = Physics { set: common, ..opts.physics.clone() };
        let setup = physics.setup(opts.n, DEFAULT_N)?;
        let envs = opts.envs.or(setup.envs).unwrap_or(1);
        if !(1..=MAX_ENVS).contains(&envs) {
            bail!("invalid envs {envs}: must be in 1 ..= {MAX_ENVS}");
        }
        let np = setup.scene.num_particles();
        if envs as usize * np > MAX_BATCH_PARTICLES {
            bail!(
                "envs {envs}: {envs} worlds of {np} particles are more than the {MAX_BATCH_PARTICLES} a batch holds; at most {} worlds of this scene",
                MAX_BATCH_PARTICLES / np.max(1)
            );
        }
        let per_world = world_lists(&setup, &opts.physics.set, per_world);
        let params = world_params(std::slice::from_ref(&setup.params), &per_world, envs as usize)?;
        for (k, p) in params.iter().enumerate() {
            clothlab_core::cloth::check_params(&setup.scene, p)
                .map_err(|e| if envs > 1 { anyhow::anyhow!("world {k}: {e}") } else { e.into() })?;
        }
        if opts.grad && envs > 1 {
            bail!("grad=True records one world for now ({} with envs {envs})", opts.backend.name());
        }
        // A single run, or a GPU batch: one solver, every world in each dispatch.
        if envs == 1 || opts.backend.is_gpu() {
            let solver = make_worlds(opts.backend, setup.scene.clone(), params, &opts.gpu, &Shared::None)?;
            let mut sim = Sim { solver, worlds: Vec::new(), backend: opts.backend, setup, gpu: opts.gpu, grad: None };
            if opts.grad {
                sim.grad = Some(Box::new(sim.new_recording()?));
            }
            return Ok(sim);
        }
        if opts.gpu.variant.is_some() {
            bail!("--preset and --set-variant choose a GPU backend's kernels, and {} is the CPU", opts.backend.name());
        }
        let mut worlds = Self::build_worlds(opts.backend, &setup.scene, &params)?;
        let first = worlds.remove(0);
        Ok(Sim {
            solver: AnySolver::Cpu(Box::new(first)),
            worlds,
            backend: opts.backend,
            setup,
            gpu: opts.gpu,
            grad: None,
        })
    }

    /// One CPU solver a world (each on one thread: the worlds are what runs in parallel),
    /// built on rayon's threads on `cpu-par`.
    fn build_worlds(backend: Backend, scene: &Scene, params: &[SimParams]) -> Result<Vec<CpuSolver>> {
        let one = |p: &SimParams| world_solver(scene, p);
        if backend == Backend::CpuPar { params.par_iter().map(one).collect() } else { params.iter().map(one).collect() }
    }

    /// How many worlds (1 for a single run).
    pub fn envs(&self) -> usize {
        match self.solver.batch_ref() {
            Some(b) => b.envs(),
            None => 1 + self.worlds.len(),
        }
    }

    /// The GPU solver's worlds where it runs a batch of more than one (`None`: a single
    /// run, or a CPU batch of a solver a world).
    fn gpu_batch(&mut self) -> Option<&mut dyn Batch> {
        self.solver.batch().filter(|b| b.envs() > 1)
    }

    /// [`Sim::gpu_batch`], to read.
    fn gpu_batch_ref(&self) -> Option<&dyn Batch> {
        self.solver.batch_ref().filter(|b| b.envs() > 1)
    }

    /// World `k` checked against the batch.
    fn check_world(&self, k: usize) -> Result<()> {
        if k >= self.envs() {
            bail!("world {k}: the batch has {} worlds (0 ..= {})", self.envs(), self.envs() - 1);
        }
        Ok(())
    }

    /// Every world's solver, world 0 first (a batch: all CPU solvers).
    fn batch(&mut self) -> Vec<&mut CpuSolver> {
        let AnySolver::Cpu(first) = &mut self.solver else {
            unreachable!("a batch of worlds is built on the CPU only")
        };
        std::iter::once(first.as_mut()).chain(self.worlds.iter_mut()).collect()
    }

    /// Runs `f` on every world, on rayon's threads on `cpu-par`; the first error is
    /// returned.
    fn each_world(&mut self, f: impl Fn(&mut dyn Solver) -> Result<()> + Sync + Send) -> Result<()> {
        if self.worlds.is_empty() {
            return f(self.solver.get());
        }
        let parallel = self.backend == Backend::CpuPar;
        let mut batch = self.batch();
        if parallel {
            batch.par_iter_mut().enumerate().try_for_each(|(k, s)| f(&mut **s).with_context(|| format!("world {k}")))
        } else {
            batch.iter_mut().enumerate().try_for_each(|(k, s)| f(&mut **s).with_context(|| format!("world {k}")))
        }
    }

    /// World `k`'s solver (a GPU batch's worlds after 0 have none of their own).
    fn world(&mut self, k: usize) -> Result<&mut dyn Solver> {
        if k > 0 && k < self.envs() && self.gpu_batch_ref().is_some() {
            bail!("world {k}: a GPU batch's worlds share one solver, which this takes for world 0 only");
        }
        match k {
            0 => Ok(self.solver.get()),
            _ if k < self.envs() => Ok(&mut self.worlds[k - 1]),
            _ => bail!("world {k}: the batch has {} worlds (0 ..= {})", self.envs(), self.envs() - 1),
        }
    }

    /// World `k`'s solver, to read.
    fn world_ref(&self, k: usize) -> Result<&dyn Solver> {
        match k {
            0 => Ok(self.solver.get_ref()),
            _ if k < self.envs() => Ok(&self.worlds[k - 1]),
            _ => bail!("world {k}: the batch has {} worlds (0 ..= {})", self.envs(), self.envs() - 1),
        }
    }

    /// The backend.
    pub fn backend(&self) -> Backend {
        self.backend
    }

    /// The solver's name (backend and variant, e.g. `vulkan`, `cpu-par`).
    pub fn name(&self) -> &str {
        if self.worlds.is_empty() { self.solver.get_ref().name() } else { self.backend.name() }
    }

    /// Where it runs: the adapter (and API), or the CPU.
    pub fn adapter(&self) -> String {
        self.solver.adapter()
    }

    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.setup.scene
    }

    /// The scene file's title, if it has one.
    pub fn title(&self) -> Option<&str> {
        self.setup.title.as_deref()
    }

    /// The cloth's topology: triangles, springs, each cloth's range.
    pub fn topology(&self) -> &ClothTopology {
        self.solver.topology()
    }

    /// The parameters in use (world 0's).
    pub fn params(&self) -> &SimParams {
        self.solver.get_ref().params()
    }

    /// World `k`'s parameters.
    pub fn world_params(&self, k: usize) -> Result<&SimParams> {
        if let Some(b) = self.gpu_batch_ref() {
            self.check_world(k)?;
            return Ok(&b.world_params()[k]);
        }
        Ok(self.world_ref(k)?.params())
    }

    /// The parameters as `NAME → value` (the names `set` takes).
    pub fn params_json(&self) -> Result<serde_json::Map<String, serde_json::Value>> {
        match serde_json::to_value(self.params())? {
            serde_json::Value::Object(m) => Ok(m),
            _ => bail!("parameters are not an object"),
        }
    }

    /// Replaces the parameters, of every world (validated against the cloth first; on
    /// error nothing changes).
    pub fn set_params(&mut self, params: SimParams) -> Result<()> {
        self.set_world_params(vec![params; self.envs()])
    }

    /// Replaces each world's parameters (one each, every one validated against the cloth
    /// first; on error nothing changes).
    fn set_world_params(&mut self, params: Vec<SimParams>) -> Result<()> {
        if params.len() != self.envs() {
            bail!("{} parameter sets for {} worlds", params.len(), self.envs());
        }
        let batch = self.envs() > 1;
        for (k, p) in params.iter().enumerate() {
            clothlab_core::cloth::check_params(&self.setup.scene, p)
                .map_err(|e| if batch { anyhow::anyhow!("world {k}: {e}") } else { e.into() })?;
        }
        // What the solvers check besides (a moving collider's speed against the substep)
        // is checked on a copy of each world's first, so that all or none change.
        if batch {
            let scene = &self.setup.scene;
            for (k, p) in params.iter().enumerate() {
                scene.check_motion_speed(p.dt()).map_err(|e| anyhow::anyhow!("world {k}: {e}"))?;
            }
        }
        if let Some(b) = self.gpu_batch() {
            return Ok(b.set_world_params(params)?);
        }
        if self.grad.is_some() {
            // What has no adjoint is refused here, not at the next frame.
            let w: Vec<f32> = self.solver.get().state()?.pos.iter().map(|x| x[3]).collect();
            clothlab_cpu::grad::Model::new(&self.setup.scene, self.topology(), &params[0], &w)
                .map_err(anyhow::Error::msg)?;
            self.check_gpu_grad()?;
        }
        if self.worlds.is_empty() {
            let p = params.into_iter().next().context("one parameter set")?;
            return Ok(self.solver.get().set_params(p)?);
        }
        for (k, (s, p)) in self.batch().into_iter().zip(params).enumerate() {
            s.set_params(p).map_err(|e| anyhow::anyhow!("world {k}: {e}"))?;
        }
        Ok(())
    }

    /// Applies `NAME=VALUE` overrides (as `--set`): every one checked, all or none applied.
    /// A value may be one per world: a list for a parameter that takes a number or a word
    /// (`damping=[0.01,0.02]`), a list of lists for one that takes a list.
    pub fn set(&mut self, sets: &[String]) -> Result<()> {
        let (common, per_world) = split_world_sets(sets);
        let mut each = Vec::with_capacity(self.envs());
        for k in 0..self.envs() {
            let p = crate::setup::apply_overrides(self.world_params(k)?, &common)?;
            each.push(p);
        }
        let params = world_params(&each, &per_world, self.envs())?;
        self.set_world_params(params)
    }

    /// Particles in the state.
    pub fn num_particles(&self) -> usize {
        self.topology().num_particles()
    }

    /// Advances `frames` frames of `params().substeps` substeps.
    pub fn step(&mut self, frames: u64) -> Result<()> {
        if frames > MAX_STEPS {
            bail!("invalid frames {frames}: must be in 0 ..= {MAX_STEPS}");
        }
        if self.grad.is_some() {
            for _ in 0..frames {
                self.record_frame_start()?;
                self.solver.get().step_frame()?;
                let ended = self.solver.get().state()?;
                if let Some(g) = &mut self.grad {
                    g.ended = Some(ended);
                }
            }
            return Ok(());
        }
        if self.worlds.is_empty() {
            for _ in 0..frames {
                self.solver.get().step_frame()?;
            }
            return Ok(());
        }
        self.each_world(|s| {
            for _ in 0..frames {
                s.step_frame()?;
            }
            Ok(())
        })
    }

    /// Advances `k` substeps, each run as a frame of one substep of the same dt (what runs
    /// once a frame — a frame's normals, its submission, its timestamps — runs after each).
    pub fn substep(&mut self, k: u64) -> Result<()> {
        if k > MAX_STEPS {
            bail!("invalid substeps {k}: must be in 0 ..= {MAX_STEPS}");
        }
        if k == 0 {
            return Ok(());
        }
        if self.grad.is_some() {
            bail!("substep: a recording for gradients steps whole frames (step)");
        }
        let whole: Vec<SimParams> = (0..self.envs()).map(|w| self.world_params(w).cloned()).collect::<Result<_>>()?;
        if whole.iter().all(|p| p.substeps == 1) {
            return self.step(k);
        }
        let single = whole.iter().map(|p| SimParams { frame_dt: p.dt(), substeps: 1, ..p.clone() }).collect();
        self.set_world_params(single).context("a frame of one substep")?;
        let stepped = self.step(k);
        self.set_world_params(whole)?;
        stepped
    }

    /// On a GPU backend, a cloth without the adjoint's buffer.
    fn check_gpu_grad(&self) -> Result<()> {
        if !self.backend.is_gpu() {
            return Ok(());
        }
        let np = self.num_particles();
        if !clothlab_engine::solver::has_adjoint(self.topology()) {
            bail!(
                "grad=True on a GPU: a cloth of {np} particles is over the {} the adjoint's buffer is made for (use cpu-par)",
                clothlab_engine::solver::TRI_BUFFERS_ALWAYS
            );
        }
        let integrator = self.params().integrator;
        if !matches!(integrator, Integrator::Verlet | Integrator::SymplecticEuler) {
            bail!(
                "grad=True on a GPU: the adjoint kernels walk verlet and symplectic-euler; integrator {}'s adjoint runs on cpu and cpu-par",
                integrator.name()
            );
        }
        Ok(())
    }

    /// A new recording from the current state with the current parameters (refused
    /// where the run uses what has no adjoint yet).
    fn new_recording(&mut self) -> Result<Grad> {
        let st = self.solver.get().state()?;
        let params = self.params().clone();
        self.check_gpu_grad()?;
        let w: Vec<f32> = st.pos.iter().map(|x| x[3]).collect();
        let model = clothlab_cpu::grad::Model::new(&self.setup.scene, self.topology(), &params, &w)
            .map_err(anyhow::Error::msg)?
            .parallel(self.backend == Backend::CpuPar);
        Ok(Grad { rec: clothlab_cpu::grad::Recording::new(model), params, w, ended: None })
    }

    /// Before a recorded frame: its starting state kept. The recording starts again where
    /// the parameters or the masses changed since it began, or the free particles' state
    /// was set since the last frame ended (the pinned particles' positions may be set
    /// between frames: each frame's are an input of their own, [`Sim::backward`]'s pins).
    fn record_frame_start(&mut self) -> Result<()> {
        let st = self.solver.get().state()?;
        let params = self.params().clone();
        let g = self.grad.as_ref().context("a recording")?;
        let w: Vec<f32> = st.pos.iter().map(|x| x[3]).collect();
        let moved = g
            .ended
            .as_ref()
            .is_some_and(|e| e.vel != st.vel || e.pos.iter().zip(&st.pos).any(|(a, b)| b[3] != 0.0 && a != b));
        if params != g.params || w != g.w {
            let fresh = self.new_recording()?;
            self.grad = Some(Box::new(fresh));
        } else if moved {
            let g = self.grad.as_mut().context("a recording")?;
            g.rec = clothlab_cpu::grad::Recording::new(g.rec.model().clone());
        }
        let g = self.grad.as_mut().context("a recording")?;
        g.rec.push(&st.pos, &st.vel);
        Ok(())
    }

    /// The gradients of a loss of the final state with respect to the recording's initial
    /// state, the parameters and each frame's pins ([`clothlab_cpu::grad::Gradients`],
    /// docs/gradients.md): `positions` and `velocities` are the loss's gradient with
    /// respect to the final positions and velocities (one row a particle; either may be
    /// `None`: zeros). Each recorded frame's substeps are recomputed from its starting
    /// state, then walked back. Refused without a recording (`grad`), before a frame was
    /// recorded, or after the state was set since the last recorded frame.
    pub fn backward(
        &mut self,
        positions: Option<&[[f32; 3]]>,
        velocities: Option<&[[f32; 3]]>,
    ) -> Result<clothlab_cpu::grad::Gradients> {
        let np = self.num_particles();
        let st = self.solver.get().state()?;
        let Some(g) = &self.grad else { bail!("backward: nothing is recorded: open the Sim with grad=True") };
        if g.rec.frames() == 0 {
            bail!("backward: no frame recorded since the recording began: step first");
        }
        if g.ended.as_ref().is_some_and(|e| e.pos != st.pos || e.vel != st.vel) {
            bail!("backward: the state was set after the last recorded frame: step, or reset_grad and step");
        }
        let zeros = vec![[0.0f32; 3]; np];
        let rows = |v: Option<&[[f32; 3]]>, what: &str| -> Result<Vec<[f32; 3]>> {
            let Some(v) = v else { return Ok(zeros.clone()) };
            if v.len() != np {
                bail!("backward: {what}: {} rows for {np} particles", v.len());
            }
            if let Some(i) = v.iter().position(|r| !r.iter().all(|c| c.is_finite())) {
                bail!("backward: {what}: row {i} is not finite");
            }
            Ok(v.to_vec())
        };
        let (xb, vb) = (rows(positions, "positions")?, rows(velocities, "velocities")?);
        if !self.backend.is_gpu() {
            return Ok(g.rec.backward(&xb, &vb));
        }
        let topo = self.topology().clone();
        let runner = self.solver.runner().context("a GPU solver's kernels")?;
        // A GPU backend: the adjoint kernels on its solver, whose buffers the walk
        // overwrites; the state put back after.
        let walked = clothlab_engine::grad::KernelWalk::new(runner, &self.setup.scene, &g.params, &topo, &st)
            .map_err(anyhow::Error::from)
            .and_then(|mut walk| g.rec.backward_by(&mut walk, &xb, &vb).map_err(anyhow::Error::msg));
        self.solver.get().set_state(&st)?;
        walked.context("backward on the GPU")
    }

    /// Starts a new recording from the current state and parameters (`grad` only).
    pub fn reset_grad(&mut self) -> Result<()> {
        if self.grad.is_none() {
            bail!("reset_grad: nothing is recorded: open the Sim with grad=True");
        }
        let fresh = self.new_recording()?;
        self.grad = Some(Box::new(fresh));
        Ok(())
    }

    /// Frames in the recording for gradients, and the bytes its checkpoints hold (`None`
    /// without `grad`).
    pub fn recorded(&self) -> Option<(usize, usize)> {
        self.grad.as_ref().map(|g| (g.rec.frames(), g.rec.bytes()))
    }

    /// Simulated time, s.
    pub fn time(&self) -> f64 {
        self.solver.get_ref().time()
    }

    /// World `k`'s simulated time, s.
    pub fn world_time(&self, k: usize) -> Result<f64> {
        if let Some(b) = self.gpu_batch_ref() {
            self.check_world(k)?;
            return Ok(b.world_time(k));
        }
        Ok(self.world_ref(k)?.time())
    }

    /// Sets the simulated time of every world (finite, ≥ 0): moving colliders and pins
    /// go where their motion puts them then.
    pub fn set_time(&mut self, t: f64) -> Result<()> {
        clothlab_core::solver::checked_time(t)?;
        self.each_world(|s| Ok(s.set_time(t)?))
    }

    /// A copy of the state (world 0's; read back from the GPU where it lives there).
    pub fn state(&mut self) -> Result<ClothState> {
        Ok(self.solver.get().state()?)
    }

    /// A copy of world `k`'s state.
    pub fn world_state(&mut self, k: usize) -> Result<ClothState> {
        if let Some(b) = self.gpu_batch() {
            return Ok(b.world_state(k)?);
        }
        Ok(self.world(k)?.state()?)
    }

    /// Every world's state, world 0 first (a GPU batch's buffers read once each).
    pub fn world_states(&mut self) -> Result<Vec<ClothState>> {
        if let Some(b) = self.gpu_batch() {
            return Ok(b.states()?);
        }
        (0..self.envs()).map(|k| self.world_state(k)).collect()
    }

    /// Replaces every world's state (one a world, each checked first).
    fn set_world_states(&mut self, states: &[ClothState]) -> Result<()> {
        for s in states {
            s.check(self.topology())?;
        }
        if let Some(b) = self.gpu_batch() {
            return Ok(b.set_states(states)?);
        }
        for (k, s) in states.iter().enumerate() {
            self.set_world_state(k, s)?;
        }
        Ok(())
    }

    /// Replaces the state (world 0's): of this cloth, finite, or refused with nothing
    /// changed.
    pub fn set_state(&mut self, state: &ClothState) -> Result<()> {
        self.set_world_state(0, state)
    }

    /// Replaces world `k`'s state: of this cloth, finite, or refused with nothing changed.
    pub fn set_world_state(&mut self, k: usize, state: &ClothState) -> Result<()> {
        state.check(self.topology())?;
        if let Some(b) = self.gpu_batch() {
            return Ok(b.set_world_state(k, state)?);
        }
        Ok(self.world(k)?.set_state(state)?)
    }

    /// Restores worlds to how they were opened — their state and their time, as a new
    /// run of the scene with their parameters starts (`None`: every world): each is built
    /// again (a GPU run's pipelines too). Each world's parameters stay; a script's pin
    /// motions go. A world named twice or past the batch is refused, nothing reset.
    pub fn reset(&mut self, worlds: Option<&[usize]>) -> Result<()> {
        let all: Vec<usize> = (0..self.envs()).collect();
        let chosen = worlds.unwrap_or(&all);
        for (i, &k) in chosen.iter().enumerate() {
            if k >= self.envs() {
                bail!("reset: world {k}: the batch has {} worlds (0 ..= {})", self.envs(), self.envs() - 1);
            }
            if chosen[..i].contains(&k) {
                bail!("reset: world {k} is named twice");
            }
        }
        // A GPU batch's world starts again where a new run of its parameters starts: its
        // state as the solver starts one, its time 0 (a moving scene's worlds share their
        // clock: only all of them together), world 0's grab let go.
        if self.gpu_batch_ref().is_some() {
            let starts: Vec<ClothState> =
                chosen.iter().map(|&k| self.start_state(self.world_params(k)?)).collect::<Result<_>>()?;
            if chosen.len() < self.envs() && self.setup.scene.moves() {
                bail!(
                    "reset: a GPU batch's worlds share the clock of the scene's moving colliders and pins: reset every world together"
                );
            }
            let mut states = self.world_states()?;
            for (&k, start) in chosen.iter().zip(starts) {
                states[k] = start;
            }
            let pins = self.setup.scene.pins.clone();
            let b = self.gpu_batch().context("a GPU batch")?;
            b.set_states(&states)?;
            // A script's motions go: each chosen world's scripted groups move as the
            // scene says again.
            for &k in chosen {
                b.set_world_time(k, 0.0)?;
                for (g, group) in pins.iter().enumerate().filter(|(_, g)| g.scripted) {
                    b.set_world_pin_motion(k, g, group.motion.clone())?;
                }
            }
            if chosen.contains(&0) {
                self.solver.get().set_grab(None);
            }
            return Ok(());
        }
        // Each chosen world is built again, as a new run starts (its caches, grab and time
        // with it): a batch's world as `build_worlds` builds it, a single run as `open`.
        for &k in chosen {
            let params = self.world_ref(k)?.params().clone();
            match k {
                0 if self.worlds.is_empty() => {
                    self.solver = make(self.backend, self.setup.scene.clone(), params, &self.gpu, &Shared::None)?;
                }
                0 => self.solver = AnySolver::Cpu(Box::new(world_solver(&self.setup.scene, &params)?)),
                _ => self.worlds[k - 1] = world_solver(&self.setup.scene, &params)?,
            }
        }
        Ok(())
    }

    /// The state a run of this scene with `params` starts from: the cloth as built, its
    /// normals and wind as every solver computes them first.
    fn start_state(&self, params: &SimParams) -> Result<ClothState> {
        let (state, topo) = clothlab_core::build(&self.setup.scene, params)?;
        let sp = clothlab_core::step_params::StepParams::new(params, &self.setup.scene, None);
        let b = clothlab_engine::cpu::start_buffers(Exec::Serial, &sp, &topo, &state);
        Ok(ClothState { n: state.n, pos: b.pos, vel: b.vel, force: b.force, normal: b.normal })
    }

    /// The reference mass inverse masses are relative to, kg (the cloth's mass over its
    /// particles).
    fn reference_mass(&self) -> f32 {
        self.params().cloth_mass / self.num_particles().max(1) as f32
    }

    /// One array of the state as it is (w: see [`ClothState`]), read back alone: every
    /// world's, world after world.
    pub fn field(&mut self, field: StateField) -> Result<Vec<[f32; 4]>> {
        if let Some(b) = self.gpu_batch() {
            return Ok(b.fields(field)?);
        }
        if self.worlds.is_empty() {
            return Ok(self.solver.get().field(field)?);
        }
        let mut all = Vec::with_capacity(self.envs() * self.num_particles());
        for s in self.batch() {
            all.extend(s.field(field)?);
        }
        Ok(all)
    }

    /// Positions, m.
    pub fn positions(&mut self) -> Result<Vec<[f32; 3]>> {
        Ok(xyz(&self.field(StateField::Pos)?))
    }

    /// Velocities, m/s.
    pub fn velocities(&mut self) -> Result<Vec<[f32; 3]>> {
        Ok(xyz(&self.field(StateField::Vel)?))
    }

    /// Unit vertex normals.
    pub fn normals(&mut self) -> Result<Vec<[f32; 3]>> {
        Ok(xyz(&self.field(StateField::Normal)?))
    }

    /// Inverse masses, 1/kg (0: pinned).
    pub fn inverse_masses(&mut self) -> Result<Vec<f32>> {
        let m = self.reference_mass();
        Ok(self.field(StateField::Pos)?.iter().map(|p| p[3] / m).collect())
    }

    /// Each world's new state: `edit` given a world's state and its rows of `values`
    /// (one per particle of every world, world after world), all checked before any
    /// world changes.
    fn set_rows<T>(
        &mut self,
        values: &[T],
        what: &str,
        edit: impl Fn(&mut ClothState, &[T]) -> Result<()>,
    ) -> Result<()> {
        let (np, envs) = (self.num_particles(), self.envs());
        if values.len() != np * envs {
            match envs {
                1 => bail!("{what}: {} rows for {np} particles", values.len()),
                _ => bail!(
                    "{what}: {} rows for {envs} worlds of {np} particles (give {}, world after world)",
                    values.len(),
                    np * envs
                ),
            }
        }
        let mut states = self.world_states()?;
        for (k, s) in states.iter_mut().enumerate() {
            edit(s, &values[k * np..(k + 1) * np])
                .map_err(|e| if envs > 1 { e.context(format!("world {k}")) } else { e })?;
        }
        self.set_world_states(&states)
    }

    /// Sets the positions, one per particle of every world, finite (inverse masses kept).
    pub fn set_positions(&mut self, x: &[[f32; 3]]) -> Result<()> {
        self.set_rows(x, "positions", |s, x| put_xyz(&mut s.pos, x, "positions"))
    }

    /// Sets the velocities, one per particle of every world, finite.
    pub fn set_velocities(&mut self, v: &[[f32; 3]]) -> Result<()> {
        self.set_rows(v, "velocities", |s, v| put_xyz(&mut s.vel, v, "velocities"))
    }

    /// Sets the inverse masses, 1/kg: one per particle of every world, finite and ≥ 0
    /// (0 pins it).
    pub fn set_inverse_masses(&mut self, w: &[f32]) -> Result<()> {
        let m = self.reference_mass();
        self.set_rows(w, "inverse masses", |s, w| {
            if let Some((i, v)) = w.iter().enumerate().find(|(_, v)| !(v.is_finite() && **v >= 0.0)) {
                bail!("inverse masses: particle {i} has {v}; an inverse mass is finite and ≥ 0");
            }
            for (p, &inv) in s.pos.iter_mut().zip(w) {
                p[3] = inv * m;
            }
            Ok(())
        })
    }

    /// The triangles, as particle indices.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.topology().triangles
    }

    /// Each cloth's particles and triangles (one range for a single grid).
    pub fn cloths(&self) -> Vec<ClothRange> {
        let parts = self.topology().parts();
        if parts.is_empty() {
            return vec![ClothRange {
                label: "cloth".into(),
                first: 0,
                count: self.num_particles() as u32,
                first_triangle: 0,
                triangles: self.topology().triangles.len() as u32,
            }];
        }
        parts
            .iter()
            .map(|p| ClothRange {
                label: p.label.clone(),
                first: p.first,
                count: p.count,
                first_triangle: p.first_triangle,
                triangles: p.triangles,
            })
            .collect()
    }

    /// Grabs `particle` and holds it at `target` (moved there every substep) until
    /// [`Sim::release`] or another grab.
    /// (In a batch, `particle` counts every world's particles, world after world: world
    /// `particle / num_particles()` grabs one; each world holds at most one.)
    pub fn grab(&mut self, particle: u32, target: [f32; 3]) -> Result<()> {
        let np = self.num_particles();
        let all = np * self.envs();
        if particle as usize >= all {
            bail!("particle {particle}: the cloth has {all} particles (0 ..= {})", all.saturating_sub(1));
        }
        if !target.iter().all(|v| v.is_finite()) {
            bail!("grab target {target:?}: a position is finite");
        }
        if self.grad.is_some() {
            bail!("grab: a grab has no adjoint yet (a recording for gradients is open: grad=True)");
        }
        let (k, particle) = (particle as usize / np.max(1), particle % np.max(1) as u32);
        if k > 0 && self.gpu_batch_ref().is_some() {
            bail!("particle {particle} of world {k}: a GPU batch holds a grab in world 0 only");
        }
        self.world(k)?.set_grab(Some(Grab { particle, target }));
        Ok(())
    }

    /// Moves `[[pins]]` group `group` — one the scene marks `scripted = true` — to `offset`
    /// (m, from where the scene placed it) turned by `rotate_deg` about its pivot (degrees
    /// about x, then y, then z, as a motion key's), over the next frame at constant speed
    /// from where it is now, and holds it there: its motion becomes those two keys
    /// (`core::pins`). In a batch, world `world`'s group, or every world's (`None`).
    pub fn set_pin_pose(
        &mut self,
        group: usize,
        offset: [f32; 3],
        rotate_deg: [f32; 3],
        world: Option<usize>,
    ) -> Result<()> {
        use clothlab_core::motion::{Key, Motion};
        let worlds: Vec<usize> = match world {
            Some(k) => vec![k],
            None => (0..self.envs()).collect(),
        };
        for k in worlds {
            self.check_world(k)?;
            let (now, frame) = (self.world_time(k)?, self.world_params(k)?.frame_dt as f64);
            let pins: &[clothlab_core::PinGroup] = match self.gpu_batch_ref() {
                Some(b) => b.world_pins(k)?,
                None => &self.world_ref(k)?.scene().pins,
            };
            let Some(g) = pins.get(group) else {
                bail!("pin group {group}: the scene has {} [[pins]] groups", pins.len());
            };
            // Where the group is now: its motion's pose (a turn as a key's angles).
            let pose = g.motion.at(now);
            let (rz, ry, rx) = pose.rotation.to_euler(glam::EulerRot::ZYX);
            let from = [rx, ry, rz].map(|a| a.to_degrees() as f32);
            let (t0, t1) = (now as f32, (now + frame) as f32);
            if t1 <= t0 {
                bail!("set_pin_pose at t = {now} s: the keys' times (f32) cannot tell a frame apart; reset the time");
            }
            let motion = Motion {
                keys: vec![Key { t: t0, offset: pose.offset, rotate_deg: from }, Key { t: t1, offset, rotate_deg }],
                ..Motion::default()
            };
            let batch = self.envs() > 1;
            let set = match self.gpu_batch() {
                Some(b) => b.set_world_pin_motion(k, group, motion),
                None => self.world(k)?.set_pin_motion(group, motion),
            };
            set.map_err(|e| {
                let e = anyhow::Error::from(e);
                if batch { e.context(format!("world {k}")) } else { e }
            })?;
        }
        Ok(())
    }

    /// Lets go of the grabbed particle (every world's).
    pub fn release(&mut self) {
        let _ = self.each_world(|s| {
            s.set_grab(None);
            Ok(())
        });
    }

    /// Per-kernel timings since the last reset (per substep; `frame` per frame).
    pub fn timings(&self) -> KernelTimings {
        self.solver.get_ref().timings()
    }

    /// Forgets the recorded timings.
    pub fn reset_timings(&mut self) {
        self.solver.get().reset_timings();
    }

    /// Edges through triangles they share no vertex with, in the current state.
    /// (In a batch: summed over the worlds.)
    pub fn crossings(&mut self) -> Result<usize> {
        let mut sum = 0;
        let (np, all) = (self.num_particles(), self.field(StateField::Pos)?);
        for pos in all.chunks_exact(np.max(1)) {
            sum += clothlab_core::crossings::count(pos, &self.topology().triangles).pairs;
        }
        Ok(sum)
    }

    /// The scene file's view in `mode` (its camera and light, else the default view).
    pub fn view(&self, mode: RenderMode) -> View {
        let mut view = crate::render::default_view(mode);
        if let Some(c) = self.setup.camera.clone() {
            view.camera = c;
        }
        if let Some(l) = self.setup.light {
            view.light = l;
        }
        view
    }

    /// The scene drawn now, RGBA8 rows from the top, through the backend's own API (wgpu
    /// for a CPU backend, or `api`), and the adapter that drew it.
    pub fn render(
        &mut self,
        width: u32,
        height: u32,
        view: &View,
        api: Option<crate::Api>,
    ) -> Result<(Vec<u8>, String)> {
        crate::render::image(&mut self.solver, &self.setup.scene, view, (width, height), api)
    }

    /// The worlds `first ..` (at most [`MOSAIC_WORLDS`], and no more than the batch has)
    /// laid out on a grid in one picture of `width` × `height`: row after row, each world
    /// drawn as [`Sim::render_world`] draws it at its tile's size (`width / cols` ×
    /// `height / rows`, `cols` the smallest whose square holds them), the rest of the
    /// picture the background's grey. Returns the picture, the adapter and the worlds
    /// drawn.
    pub fn render_worlds(
        &mut self,
        first: usize,
        width: u32,
        height: u32,
        view: &View,
        api: Option<crate::Api>,
    ) -> Result<(Vec<u8>, String, std::ops::Range<usize>)> {
        if first >= self.envs() {
            bail!("world {first}: the batch has {} worlds (0 ..= {})", self.envs(), self.envs() - 1);
        }
        let worlds = first..self.envs().min(first + MOSAIC_WORLDS);
        let (cols, rows) = mosaic_grid(worlds.len());
        let (tw, th) = (width / cols, height / rows);
        if tw == 0 || th == 0 {
            bail!("a picture of {width}x{height} cannot hold {} worlds on a {cols}x{rows} grid", worlds.len());
        }
        let mut out = vec![0u8; width as usize * height as usize * 4];
        for px in out.chunks_exact_mut(4) {
            px.copy_from_slice(&MOSAIC_BACKGROUND);
        }
        let mut adapter = String::new();
        for (i, k) in worlds.clone().enumerate() {
            let (tile, a) = self.render_world(k, tw, th, view, api)?;
            adapter = a;
            let (x0, y0) = ((i as u32 % cols) * tw, (i as u32 / cols) * th);
            for y in 0..th {
                let from = (y * tw * 4) as usize;
                let to = (((y0 + y) * width + x0) * 4) as usize;
                out[to..to + (tw * 4) as usize].copy_from_slice(&tile[from..from + (tw * 4) as usize]);
            }
        }
        Ok((out, adapter, worlds))
    }

    /// World `k`'s picture, as [`Sim::render`] draws world 0.
    pub fn render_world(
        &mut self,
        k: usize,
        width: u32,
        height: u32,
        view: &View,
        api: Option<crate::Api>,
    ) -> Result<(Vec<u8>, String)> {
        if k >= self.envs() {
            bail!("world {k}: the batch has {} worlds (0 ..= {})", self.envs(), self.envs() - 1);
        }
        if k == 0 {
            return self.render(width, height, view, api);
        }
        // A GPU batch's world k: its state read back, drawn as a CPU solver holding it draws
        // (the renderer draws a solver's world 0).
        if self.gpu_batch_ref().is_some() {
            let params = self.world_params(k)?.clone();
            let (state, time) = (self.world_state(k)?, self.world_time(k)?);
            let mut world = CpuSolver::new(Exec::Serial, self.setup.scene.clone(), params)?;
            world.set_state(&state)?;
            world.set_time(time)?;
            let mut solver = AnySolver::Cpu(Box::new(world));
            return crate::render::image(&mut solver, &self.setup.scene, view, (width, height), api);
        }
        // World k takes world 0's place for the picture (a batch's worlds are all CPU
        // solvers), and goes back after it.
        let AnySolver::Cpu(first) = &mut self.solver else {
            unreachable!("a batch of worlds is built on the CPU only")
        };
        std::mem::swap(first.as_mut(), &mut self.worlds[k - 1]);
        let drawn = self.render(width, height, view, api);
        let AnySolver::Cpu(first) = &mut self.solver else {
            unreachable!("a batch of worlds is built on the CPU only")
        };
        std::mem::swap(first.as_mut(), &mut self.worlds[k - 1]);
        drawn
    }

    /// Runs `frames` frames recording every `every`-th (and the first) and writes them to
    /// `path` as binary glTF (as `sim --record`): world `world` of a batch, or with `None`
    /// every world, laid out on a grid ([`crate::record::glb_worlds`]); returns the frames
    /// kept.
    pub fn record(&mut self, path: &Path, frames: u64, every: u32, world: Option<usize>) -> Result<usize> {
        if frames > MAX_STEPS {
            bail!("invalid frames {frames}: must be in 0 ..= {MAX_STEPS}");
        }
        let mut rec = self.recorder(path, frames, every, world)?;
        self.record_frame(&mut rec, 0)?;
        for f in 1..=frames {
            self.step(1)?;
            self.record_frame(&mut rec, f)?;
        }
        Ok(rec.finish(self.topology(), &self.setup.scene)?.1)
    }

    /// Gives `rec` frame `frame` of the worlds it records, as they are now (a GPU batch's
    /// read at once: a world at a time would read every world's rows each time).
    pub fn record_frame(&mut self, rec: &mut Recorder, frame: u64) -> Result<()> {
        if self.gpu_batch_ref().is_some() {
            let states = self.world_states()?;
            return rec.frame(frame, |k| Ok(states[k].clone()));
        }
        rec.frame(frame, |k| self.world_state(k))
    }

    /// A recording of a run of `frames` frames of this simulation ([`Recorder`]: of world
    /// `world`, or of every world), checked before the run: the file name, the world, the
    /// worlds' frame times, the size.
    pub fn recorder(&self, path: &Path, frames: u64, every: u32, world: Option<usize>) -> Result<Recorder> {
        let frame_dt =
            (0..self.envs()).map(|k| self.world_params(k).map(|p| p.frame_dt)).collect::<Result<Vec<_>>>()?;
        Recorder::new(path, frames, every, world, &frame_dt, self.num_particles(), self.topology().triangles.len())
    }

    /// The solver, for what the facade does not wrap (its kernels, its buffers).
    pub fn solver(&mut self) -> &mut AnySolver {
        &mut self.solver
    }
}

/// A batch's world: a CPU solver on one thread (the worlds are what runs in parallel),
/// without per-kernel timing.
fn world_solver(scene: &Scene, params: &SimParams) -> Result<CpuSolver> {
    let mut s = CpuSolver::new(Exec::Serial, scene.clone(), params.clone())?;
    s.time_kernels = false;
    Ok(s)
}

/// The first three components of each.
fn xyz(v: &[[f32; 4]]) -> Vec<[f32; 3]> {
    v.iter().map(|p| [p[0], p[1], p[2]]).collect()
}

/// Writes `x` into the first three components of `dst`: one per particle, finite.
fn put_xyz(dst: &mut [[f32; 4]], x: &[[f32; 3]], what: &str) -> Result<()> {
    if x.len() != dst.len() {
        bail!("{what}: {} rows for {} particles", x.len(), dst.len());
    }
    if let Some(i) = x.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
        bail!("{what}: particle {i} has {:?}; every value is finite", x[i]);
    }
    for (d, s) in dst.iter_mut().zip(x) {
        d[..3].copy_from_slice(s);
    }
    Ok(())
}

/// What this machine can run: every backend with its adapter, or why it cannot run.
pub fn available() -> Vec<(Backend, Result<String, String>)> {
    let wgpu = clothlab_wgpu::GpuContext::new().map(|c| c.describe()).map_err(|e| e.to_string());
    let vulkan =
        clothlab_vulkan::Device::new(false).map(|d| format!("{} (Vulkan)", d.name())).map_err(|e| e.to_string());
    let gl = clothlab_gl::GlEngine::new().map(|e| e.describe()).map_err(|e| e.to_string());
    let cpu = Ok(crate::bench::cpu_label());
    Backend::ALL
        .into_iter()
        .map(|b| {
            let r = match b.api() {
                None => cpu.clone(),
                Some(crate::Api::Wgpu) => wgpu.clone(),
                Some(crate::Api::Vulkan) => vulkan.clone(),
                Some(crate::Api::Gl) => gl.clone(),
            };
            (b, r)
        })
        .collect()
}

/// The most worlds [`Sim::render_worlds`] lays out in one picture (an 8 × 8 grid).
pub const MOSAIC_WORLDS: usize = 64;

/// The grey between and around the tiles of [`Sim::render_worlds`], RGBA.
const MOSAIC_BACKGROUND: [u8; 4] = [40, 40, 40, 255];

/// Columns and rows of the grid that holds `m` tiles: the fewest columns whose square
/// holds them, then the rows they fill.
fn mosaic_grid(m: usize) -> (u32, u32) {
    let cols = (1..).find(|c: &usize| c * c >= m.max(1)).unwrap_or(1);
    (cols as u32, m.max(1).div_ceil(cols) as u32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::setup::SceneSource;

    fn scenes() -> std::path::PathBuf {
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes")
    }

    fn open(file: &str, backend: Backend, n: u32, envs: u32, sets: &[&str]) -> Result<Sim> {
        Sim::open(SimOptions {
            backend,
            physics: Physics {
                scene: SceneSource::File(scenes().join(file)),
                set: sets.iter().map(|s| s.to_string()).collect(),
                ..Default::default()
            },
            n: Some(n),
            envs: Some(envs),
            ..Default::default()
        })
    }

    /// `Some(sim)`, or `None` where it is a GPU one and there is no adapter and none is
    /// required (`CLOTHLAB_REQUIRE_GPU`).
    pub(super) fn or_skip(sim: Result<Sim>) -> Option<Sim> {
        match sim {
            Ok(s) => Some(s),
            Err(e) => {
                assert!(std::env::var("CLOTHLAB_REQUIRE_GPU").as_deref() != Ok("1"), "{e:#}");
                eprintln!("no adapter here: {e:#}");
                None
            }
        }
    }

    /// The bits of a state's positions and velocities.
    fn bits(s: &ClothState) -> Vec<u32> {
        s.pos.iter().chain(&s.vel).flatten().map(|v| v.to_bits()).collect()
    }

    #[test]
    fn world_k_of_a_batch_is_a_single_run_with_its_parameters_bit_for_bit() {
        // The default scene (springs, pins, spheres, floor) under Verlet, XPBD and VBD, each
        // world with its own damping and wind; the thin heap with the contact between
        // triangles, two worlds of one place: each sees only itself.
        let cases: [(&str, u32, &[&str], u64); 4] = [
            (
                "thesis.toml",
                10,
                &["integrator=\"verlet\"", "damping=[0,0.003,0.01]", "wind=[[0,0,0],[2,0,1],[0,0,-3]]"],
                12,
            ),
            (
                "thesis.toml",
                10,
                &["integrator=\"xpbd\"", "damping=[0,0.003,0.01]", "structural_stiffness=[0.45,0.3,0.2]"],
                12,
            ),
            ("thesis.toml", 10, &["integrator=\"vbd\"", "damping=[0,0.003,0.01]", "air_drag=[0,0.2,1]"], 12),
            ("thin-heap.toml", 12, &["static_friction=[0.1,0.6,0.3]"], 30),
        ];
        for (file, n, sets, frames) in cases {
            let envs = 3;
            let mut batch = open(file, Backend::CpuPar, n, envs, sets).unwrap_or_else(|e| panic!("{file}: {e:#}"));
            batch.step(frames).unwrap();
            for k in 0..envs as usize {
                // The single run: the world's own value of each list.
                let one: Vec<String> = sets
                    .iter()
                    .map(|s| {
                        let (name, raw) = s.split_once('=').unwrap();
                        match serde_json::from_str::<serde_json::Value>(raw).unwrap() {
                            serde_json::Value::Array(v) => format!("{name}={}", v[k]),
                            _ => s.to_string(),
                        }
                    })
                    .collect();
                let one: Vec<&str> = one.iter().map(|s| s.as_str()).collect();
                let mut single = open(file, Backend::Cpu, n, 1, &one).unwrap();
                single.step(frames).unwrap();
                let (a, b) = (batch.world_state(k).unwrap(), single.state().unwrap());
                assert!(bits(&a) == bits(&b), "{file} {sets:?}: world {k} differs from its single run");
                assert_eq!(
                    clothlab_core::crossings::count(&a.pos, &single.topology().triangles).pairs,
                    0,
                    "{file}: world {k} crossed"
                );
            }
            // The worlds differ (each its own parameters), so the comparison saw something.
            assert!(bits(&batch.world_state(0).unwrap()) != bits(&batch.world_state(2).unwrap()), "{file}");
        }
    }

    #[test]
    fn a_worlds_single_run_takes_its_value_of_every_list_the_files_and_the_command_lines() {
        // The file gives damping per world and the command line wind per world and the
        // drag once; the command line's damping list would replace the file's.
        let toml = "envs = 3\n[cloth]\nn = 6\n[params]\ndamping = [0.0, 0.01, 0.1]\nair_drag = [0.1, 0.2, 0.3]\n";
        let opts = |set: &[&str]| SimOptions {
            backend: Backend::Cpu,
            physics: Physics {
                scene: SceneSource::Toml(toml.into()),
                set: set.iter().map(|s| s.to_string()).collect(),
                ..Default::default()
            },
            ..Default::default()
        };
        let batch = opts(&["wind=[[0,0,0],[3,0,0],[0,0,-2]]", "air_drag=0.5"]);
        let one = Sim::open(batch.world(1).unwrap()).unwrap();
        assert_eq!(one.envs(), 1);
        let p = one.params();
        assert_eq!((p.damping, p.wind, p.air_drag), (0.01, [3.0, 0.0, 0.0], 0.5));
        let all = Sim::open(batch).unwrap();
        assert_eq!(all.world_params(1).unwrap(), p, "world 1's parameters are its single run's");
        let replaced = opts(&["damping=[0.2,0.3,0.4]"]).world(2).unwrap();
        let p = Sim::open(replaced).unwrap().params().clone();
        assert_eq!((p.damping, p.air_drag), (0.4, 0.3));
        let err = opts(&["damping=[0.2,0.3]"]).world(1).unwrap_err().to_string();
        assert!(err.contains("`damping` has 2 values for 3 worlds"), "{err}");
        let err = opts(&[]).world(3).unwrap_err().to_string();
        assert!(err.contains("world 3: the batch has 3 worlds"), "{err}");
    }

    #[test]
    fn each_world_falls_freely_by_its_own_gravity() {
        // Verlet's free fall from rest: the drop after k substeps is g dt² k(k+1)/2 (the
        // recurrence free_fall.rs checks), here per world; the springs' forces sum to zero.
        // On cpu-par (a solver a world) and on a Vulkan batch (each world's gravity in its
        // element of the step constants' array).
        let g = [9.81f64, 4.0, 1.0];
        for backend in [Backend::CpuPar, Backend::Vulkan] {
            let Some(mut sim) =
                or_skip(open("free-fall.toml", backend, 8, 3, &["gravity=[[0,-9.81,0],[0,-4,0],[0,-1,0]]"]))
            else {
                continue;
            };
            let y0: Vec<f64> = (0..3).map(|k| mean_y(&sim.world_state(k).unwrap())).collect();
            sim.step(30).unwrap();
            let p = sim.params().clone();
            let (dt, steps) = (p.dt() as f64, 30.0 * p.substeps as f64);
            for k in 0..3 {
                let drop = y0[k] - mean_y(&sim.world_state(k).unwrap());
                let exact = g[k] * dt * dt * steps * (steps + 1.0) / 2.0;
                // f32 positions summed over 30 frames: well within 1e-4 of the drop.
                let b = backend.name();
                assert!((drop - exact).abs() < 1e-4 * exact, "{b} world {k}: fell {drop} m, the recurrence {exact} m");
            }
        }
    }

    fn mean_y(s: &ClothState) -> f64 {
        s.pos.iter().map(|p| p[1] as f64).sum::<f64>() / s.pos.len() as f64
    }

    #[test]
    fn a_reset_world_starts_again_as_a_new_run_and_the_others_go_on() {
        // On the CPU (a solver a world, built again) and on a GPU batch (one solver: the
        // world's rows rewritten with a new run's start state).
        for backend in [Backend::Cpu, Backend::Vulkan] {
            let Some(mut batch) = or_skip(open("thesis.toml", backend, 8, 2, &["damping=[0.001,0.004]"])) else {
                continue;
            };
            batch.step(5).unwrap();
            batch.reset(Some(&[1])).unwrap();
            assert_eq!(batch.world_time(1).unwrap(), 0.0);
            batch.step(5).unwrap();
            let mut fresh = open("thesis.toml", backend, 8, 2, &["damping=[0.001,0.004]"]).unwrap();
            fresh.step(5).unwrap();
            let b = backend.name();
            assert!(
                bits(&batch.world_state(1).unwrap()) == bits(&fresh.world_state(1).unwrap()),
                "{b}: world 1 after reset"
            );
            fresh.step(5).unwrap();
            assert!(
                bits(&batch.world_state(0).unwrap()) == bits(&fresh.world_state(0).unwrap()),
                "{b}: world 0 went on"
            );
            assert_eq!(batch.world_time(0).unwrap(), fresh.world_time(0).unwrap());
            // Refused, nothing reset.
            for (worlds, says) in [(&[2usize][..], "world 2: the batch has 2 worlds"), (&[0, 0][..], "named twice")] {
                let e = batch.reset(Some(worlds)).unwrap_err().to_string();
                assert!(e.contains(says), "{b}: {e}");
            }
        }
        // A GPU run is built again too: after a reset it steps as a new run does.
        match open("thesis.toml", Backend::Vulkan, 8, 1, &[]) {
            Ok(mut gpu) => {
                gpu.step(3).unwrap();
                gpu.reset(None).unwrap();
                assert_eq!(gpu.time(), 0.0);
                gpu.step(2).unwrap();
                let mut fresh = open("thesis.toml", Backend::Vulkan, 8, 1, &[]).unwrap();
                fresh.step(2).unwrap();
                assert!(bits(&gpu.state().unwrap()) == bits(&fresh.state().unwrap()), "vulkan after reset");
            }
            Err(e) => {
                assert!(std::env::var("CLOTHLAB_REQUIRE_GPU").as_deref() != Ok("1"), "{e:#}");
                eprintln!("no Vulkan here: {e:#}");
            }
        }
    }

    #[test]
    fn a_batch_s_arrays_hold_every_world_and_bad_rows_are_refused_with_nothing_changed() {
        for backend in [Backend::Cpu, Backend::Vulkan] {
            let Some(mut sim) = or_skip(open("thesis.toml", backend, 4, 3, &[])) else { continue };
            let np = sim.num_particles();
            let x = sim.positions().unwrap();
            assert_eq!(x.len(), 3 * np);
            let moved: Vec<[f32; 3]> = x.iter().enumerate().map(|(i, p)| [p[0] + i as f32, p[1], p[2]]).collect();
            sim.set_positions(&moved).unwrap();
            assert_eq!(sim.positions().unwrap(), moved);
            assert_eq!(sim.world_state(2).unwrap().pos[0][0], moved[2 * np][0]);
            let e = sim.set_positions(&moved[..np]).unwrap_err().to_string();
            assert!(e.contains(&format!("{np} rows for 3 worlds of {np} particles")), "{e}");
            let mut bad = moved.clone();
            bad[2 * np + 1][1] = f32::NAN;
            let e = format!("{:#}", sim.set_positions(&bad).unwrap_err());
            assert!(e.contains("world 2") && e.contains("particle 1"), "{e}");
            assert_eq!(sim.positions().unwrap(), moved, "nothing changed");
            // One world's bad value in a sweep: refused naming it, no world changed.
            let e = sim.set(&["damping=[0.1,0.2,0.9]".into()]).unwrap_err().to_string();
            assert!(e.contains("world 2"), "{e}");
            assert!((0..3).all(|k| sim.world_params(k).unwrap().damping == SimParams::default().damping));
            sim.set(&["damping=[0.1,0.2,0.3]".into()]).unwrap();
            assert_eq!(sim.world_params(2).unwrap().damping, 0.3);
        }
    }

    #[test]
    fn a_scene_file_asks_for_worlds_and_the_options_override_it() {
        let text = |envs: u32| format!("envs = {envs}\n[cloth]\nn = 4\n");
        let opts = |envs: u32, over: Option<u32>| SimOptions {
            physics: Physics { scene: SceneSource::Toml(text(envs)), ..Default::default() },
            envs: over,
            ..Default::default()
        };
        assert_eq!(Sim::open(opts(5, None)).unwrap().envs(), 5);
        assert_eq!(Sim::open(opts(5, Some(2))).unwrap().envs(), 2);
        let e = Sim::open(opts(0, None)).err().expect("refused").to_string();
        assert!(e.contains("<scene text>:1:") && e.contains("`envs` = 0"), "{e}");
    }

    /// A free cloth hanging from a scripted top edge, no floor.
    const SCRIPTED: &str = "[cloth]\nn = 8\nsize = 1.0\ntop_center = [0.0, 2.0, 0.0]\nacross = [1.0, 0.0, 0.0]\ndown = [0.0, -1.0, 0.0]\npinning = \"none\"\n[floor]\nenabled = false\n[[pins]]\nmin = [-0.6, 1.99, -0.01]\nmax = [0.6, 2.01, 0.01]\nscripted = true\n";

    fn scripted(backend: Backend, envs: u32) -> Result<Sim> {
        Sim::open(SimOptions {
            backend,
            physics: Physics { scene: SceneSource::Toml(SCRIPTED.into()), ..Default::default() },
            envs: Some(envs),
            ..Default::default()
        })
    }

    /// The pinned particles (the top edge, row 0) of a state.
    fn top(s: &ClothState) -> Vec<[f32; 4]> {
        s.pos[..8].to_vec()
    }

    #[test]
    fn a_script_moves_a_pin_group_over_a_frame_and_holds_it_on_every_backend_alike() {
        let mut cpu = scripted(Backend::Cpu, 1).unwrap();
        let rest = top(&cpu.state().unwrap());
        // Untouched, a scripted group stays where it was placed (to a rounding).
        cpu.step(1).unwrap();
        for (a, b) in top(&cpu.state().unwrap()).iter().zip(&rest) {
            assert!((0..3).all(|k| (a[k] - b[k]).abs() < 1e-6), "{a:?} {b:?}");
        }
        cpu.set_pin_pose(0, [0.25, 0.0, 0.0], [0.0, 0.0, 90.0], None).unwrap();
        cpu.step(2).unwrap();
        // A quarter turn about z at the pivot (the edge's centre, (0, 2, 0)) then 0.25 m
        // along x: a pin at (x, 2, 0) goes to (0.25, 2 + x, 0). The keys' f32 times and
        // the pose's f32 rotation: within 2e-6 m.
        for (a, b) in top(&cpu.state().unwrap()).iter().zip(&rest) {
            let want = [0.25, 2.0 + b[0], 0.0];
            assert!((0..3).all(|k| (a[k] - want[k]).abs() < 2e-6), "{a:?} want {want:?}");
        }
        // Held there: a frame later the pins have not moved.
        let held = top(&cpu.state().unwrap());
        cpu.step(1).unwrap();
        assert_eq!(top(&cpu.state().unwrap()), held);
        // The others are refused in one line.
        let e = cpu.set_pin_pose(1, [0.0; 3], [0.0; 3], None).unwrap_err().to_string();
        assert!(e.contains("pin group 1: the scene has 1 [[pins]] groups"), "{e}");
        let mut plain = Sim::open(SimOptions {
            physics: Physics {
                scene: SceneSource::Toml(SCRIPTED.replace("scripted = true", "")),
                ..Default::default()
            },
            ..Default::default()
        })
        .unwrap();
        let e = plain.set_pin_pose(0, [0.0; 3], [0.0; 3], None).unwrap_err().to_string();
        assert!(e.contains("scripted = true"), "{e}");
        // A GPU backend computes the CPU's bits (the same poses from the same keys).
        match scripted(Backend::Vulkan, 1) {
            Ok(mut gpu) => {
                let mut cpu = scripted(Backend::Cpu, 1).unwrap();
                for s in [&mut cpu, &mut gpu] {
                    s.step(1).unwrap();
                    s.set_pin_pose(0, [0.25, 0.0, 0.0], [0.0, 0.0, 90.0], None).unwrap();
                    s.step(2).unwrap();
                }
                assert!(bits(&cpu.state().unwrap()) == bits(&gpu.state().unwrap()), "vulkan differs from cpu");
            }
            Err(e) => {
                assert!(std::env::var("CLOTHLAB_REQUIRE_GPU").as_deref() != Ok("1"), "{e:#}");
                eprintln!("no Vulkan here: {e:#}");
            }
        }
    }

    #[test]
    fn in_a_batch_a_script_moves_each_world_s_group_its_own_way() {
        // On the CPU (a solver a world) and in a Vulkan batch (one pins dispatch for every
        // world, each world's poses its own block): world k is the single run that the
        // same script moves, on the same backend, bit for bit.
        for backend in [Backend::CpuPar, Backend::Vulkan] {
            let mut batch = match scripted(backend, 3) {
                Ok(b) => b,
                Err(e) => {
                    assert!(std::env::var("CLOTHLAB_REQUIRE_GPU").as_deref() != Ok("1"), "{e:#}");
                    eprintln!("no {backend:?} here: {e:#}");
                    continue;
                }
            };
            let single = if backend == Backend::CpuPar { Backend::Cpu } else { backend };
            let (shift, turn) = (([0.1, 0.0, 0.0], [0.0; 3]), ([0.0, -0.05, 0.1], [0.0, 30.0, 0.0]));
            batch.set_pin_pose(0, shift.0, shift.1, Some(1)).unwrap();
            batch.set_pin_pose(0, turn.0, turn.1, Some(2)).unwrap();
            batch.step(2).unwrap();
            for (k, pose) in [(1, shift), (2, turn)] {
                let mut one = scripted(single, 1).unwrap();
                one.set_pin_pose(0, pose.0, pose.1, None).unwrap();
                one.step(2).unwrap();
                let what = format!("{backend:?}: world {k} moved as a single run");
                assert!(bits(&batch.world_state(k).unwrap()) == bits(&one.state().unwrap()), "{what}");
            }
            let mut still = scripted(single, 1).unwrap();
            still.step(2).unwrap();
            let want = bits(&still.state().unwrap());
            assert!(bits(&batch.world_state(0).unwrap()) == want, "{backend:?}: world 0 left alone");
            // Reset, the script's motions go: every world is the still run again.
            batch.reset(None).unwrap();
            batch.step(2).unwrap();
            for k in 0..3 {
                assert!(bits(&batch.world_state(k).unwrap()) == want, "{backend:?}: world {k} after reset");
            }
            // A GPU batch holds its worlds' poses for the substeps it opened with (16).
            let more = batch.set(&["substeps=32".into()]);
            if backend == Backend::Vulkan {
                let e = format!("{:#}", more.unwrap_err());
                assert!(e.contains("poses for 16 substeps") && !e.contains('\n'), "{e}");
                assert_eq!(batch.world_params(1).unwrap().substeps, 16, "nothing changed");
            }
        }
    }

    #[test]
    fn a_scene_file_gives_one_value_per_world_and_the_command_line_overrides_it() {
        let text = "envs = 3\n[cloth]\nn = 4\n[params]\ndamping = [0.0, 0.002, 0.01]\nwind = [[1, 0, 0], [0, 0, 0], [0, 0, 2]]\nsubsteps = 8\n";
        let open = |set: &[&str]| {
            Sim::open(SimOptions {
                physics: Physics {
                    scene: SceneSource::Toml(text.into()),
                    set: set.iter().map(|s| s.to_string()).collect(),
                    ..Default::default()
                },
                ..Default::default()
            })
        };
        let sim = open(&[]).unwrap();
        let damping: Vec<f32> = (0..3).map(|k| sim.world_params(k).unwrap().damping).collect();
        assert_eq!(damping, [0.0, 0.002, 0.01]);
        assert_eq!(sim.world_params(2).unwrap().wind, [0.0, 0.0, 2.0]);
        assert!((0..3).all(|k| sim.world_params(k).unwrap().substeps == 8), "the rest as a single file's");
        // The command line's value for every world, or its own list, wins.
        let sim = open(&["damping=0.005"]).unwrap();
        assert!((0..3).all(|k| sim.world_params(k).unwrap().damping == 0.005));
        let sim = open(&["damping=[0.1,0.2,0.3]"]).unwrap();
        assert_eq!(sim.world_params(1).unwrap().damping, 0.2);
        // A list that does not fit the worlds, or a world's bad value: refused in one line.
        let e = open(&["wind=[[0,0,0]]"]).err().expect("refused").to_string();
        assert!(e.contains("`wind` has 1 value for 3 worlds"), "{e}");
        let bad = text.replace("0.01]", "0.9]");
        let e = Sim::open(SimOptions {
            physics: Physics { scene: SceneSource::Toml(bad), ..Default::default() },
            ..Default::default()
        })
        .err()
        .expect("refused")
        .to_string();
        assert!(e.contains("world 2: invalid parameter `damping` = 0.9"), "{e}");
    }

    #[test]
    fn a_batch_draws_any_world_as_its_single_run_draws() {
        let mut batch = open("thesis.toml", Backend::Cpu, 8, 2, &["wind=[[0,0,0],[4,0,3]]"]).unwrap();
        let mut single = open("thesis.toml", Backend::Cpu, 8, 1, &["wind=[4,0,3]"]).unwrap();
        batch.step(5).unwrap();
        single.step(5).unwrap();
        let view = single.view(RenderMode::Triangles);
        let one = match single.render(64, 48, &view, None) {
            Ok((pixels, _)) => pixels,
            Err(e) => {
                assert!(std::env::var("CLOTHLAB_REQUIRE_GPU").as_deref() != Ok("1"), "{e:#}");
                return eprintln!("no wgpu adapter here: {e:#}");
            }
        };
        let (world1, _) = batch.render_world(1, 64, 48, &view, None).unwrap();
        assert!(world1 == one, "world 1's picture is its single run's");
        let (world0, _) = batch.render_world(0, 64, 48, &view, None).unwrap();
        assert!(world0 != one, "world 0 (no wind) looks otherwise");
        // Drawn and put back: world 1 still steps as its single run.
        batch.step(1).unwrap();
        single.step(1).unwrap();
        assert!(bits(&batch.world_state(1).unwrap()) == bits(&single.state().unwrap()));
        let e = batch.render_world(2, 64, 48, &view, None).unwrap_err().to_string();
        assert!(e.contains("world 2: the batch has 2 worlds"), "{e}");
    }

    #[test]
    fn a_batch_laid_out_on_a_grid_draws_each_world_in_its_tile_as_alone() {
        // Five worlds of different winds on a 3 × 2 grid: tile k is world k's picture at
        // the tile's size, pixel for pixel; the sixth tile is the background.
        let winds = "wind=[[0,0,0],[2,0,0],[4,0,3],[0,0,4],[-3,0,2]]";
        let mut batch = open("thesis.toml", Backend::Cpu, 8, 5, &[winds]).unwrap();
        batch.step(4).unwrap();
        let view = batch.view(RenderMode::Triangles);
        let (w, h) = (96, 64);
        let (grid, _, drawn) = match batch.render_worlds(0, w, h, &view, None) {
            Ok(r) => r,
            Err(e) => {
                assert!(std::env::var("CLOTHLAB_REQUIRE_GPU").as_deref() != Ok("1"), "{e:#}");
                return eprintln!("no wgpu adapter here: {e:#}");
            }
        };
        assert_eq!(drawn, 0..5);
        assert_eq!(super::mosaic_grid(5), (3, 2));
        let (tw, th) = (w / 3, h / 2);
        let tile = |i: u32| -> Vec<u8> {
            let (x0, y0) = ((i % 3) * tw, (i / 3) * th);
            (0..th).flat_map(|y| grid[(((y0 + y) * w + x0) * 4) as usize..][..(tw * 4) as usize].to_vec()).collect()
        };
        for k in 0..5 {
            let (alone, _) = batch.render_world(k, tw, th, &view, None).unwrap();
            assert!(tile(k as u32) == alone, "tile {k} is not world {k}'s picture");
        }
        assert!(tile(0) != tile(2), "two worlds of different winds look alike");
        assert!(tile(5).chunks(4).all(|p| p == super::MOSAIC_BACKGROUND), "the empty tile is not the background");
        assert_eq!(super::mosaic_grid(64), (8, 8));
        assert_eq!(super::mosaic_grid(1), (1, 1));
        let e = batch.render_worlds(0, 2, 2, &view, None).unwrap_err().to_string();
        assert!(e.contains("cannot hold 5 worlds"), "{e}");
    }
}

#[cfg(test)]
mod grad_tests {
    use super::*;
    use crate::setup::SceneSource;

    fn opts(backend: Backend, set: &[&str]) -> SimOptions {
        SimOptions {
            backend,
            physics: Physics {
                scene: SceneSource::Default,
                set: set.iter().map(|s| s.to_string()).collect(),
                ..Default::default()
            },
            n: Some(8),
            grad: true,
            ..Default::default()
        }
    }

    #[test]
    fn a_recorded_sim_s_gradient_is_its_recording_s_and_follows_what_changes_between_frames() {
        // The default scene at n = 8 without the strain limit, 6 frames on cpu-par: the
        // gradient of the mean height by gravity's y is positive and below the closed
        // form's free fall (the held corners and the springs hold the cloth up: the
        // mean falls less than freely: 0 < d < dt² Σ (1 − r^k)/(1 − r); measured 0.93 of it).
        let mut sim = Sim::open(opts(Backend::CpuPar, &["strain_iterations=0"])).unwrap();
        sim.step(6).unwrap();
        let np = sim.num_particles();
        let loss = vec![[0.0, 1.0 / np as f32, 0.0]; np];
        let g = sim.backward(Some(&loss), None).unwrap();
        assert_eq!(sim.recorded().unwrap().0, 6);
        let dy = g.params.iter().find(|(n, _)| *n == "gravity[1]").unwrap().1;
        let p = sim.params();
        let (dt, n) = (p.dt() as f64, 6 * p.substeps as i32);
        let r = 1.0 - p.damping as f64 - p.air_drag as f64 * dt;
        let free: f64 = (1..=n).map(|k| dt * dt * (1.0 - r.powi(k)) / (1.0 - r)).sum();
        println!("d mean y / d g_y = {dy:.6} (free fall {free:.6})");
        assert!(dy > 0.1 * free && dy < free, "{dy} against free fall's {free}");
        assert_eq!(g.pins.len(), 6);
        assert_eq!(g.pinned.len(), 2, "the default scene holds two corners");
        // Setting the pinned particles' positions between frames keeps the recording (they
        // are each frame's input); setting a free particle's starts a new one.
        let mut x = sim.positions().unwrap();
        x[g.pinned[0] as usize][0] += 0.01;
        sim.set_positions(&x).unwrap();
        sim.step(1).unwrap();
        assert_eq!(sim.recorded().unwrap().0, 7, "moving a pin started a new recording");
        let mut x = sim.positions().unwrap();
        x[np / 2][1] += 0.01;
        sim.set_positions(&x).unwrap();
        let e = sim.backward(Some(&loss), None).unwrap_err().to_string();
        assert!(e.contains("state was set after the last recorded frame"), "{e}");
        sim.step(2).unwrap();
        assert_eq!(sim.recorded().unwrap().0, 2, "a free particle moved: a new recording");
        // Changing a parameter starts one too; one without an adjoint is refused.
        sim.set(&["damping=0.01".into()]).unwrap();
        sim.step(1).unwrap();
        assert_eq!(sim.recorded().unwrap().0, 1);
        let e = sim.set(&["wind=[1,0,0]".into()]).unwrap_err().to_string();
        assert!(e.contains("wind has no adjoint yet"), "{e}");
        sim.reset_grad().unwrap();
        assert_eq!(sim.recorded().unwrap().0, 0);
        let e = sim.backward(None, None).unwrap_err().to_string();
        assert!(e.contains("no frame recorded"), "{e}");
    }

    #[test]
    fn what_a_recording_cannot_take_is_refused_in_one_line() {
        let one_line = |e: anyhow::Error| {
            let e = format!("{e:#}");
            assert!(!e.contains('\n'), "{e}");
            e
        };
        let e = one_line(Sim::open(opts(Backend::Cpu, &["integrator=xpbd"])).err().unwrap());
        assert!(e.contains("integrator xpbd has no adjoint yet"), "{e}");
        let e = one_line(
            Sim::open(SimOptions { envs: Some(2), ..opts(Backend::Cpu, &["strain_iterations=0"]) }).err().unwrap(),
        );
        assert!(e.contains("one world"), "{e}");
        // A GPU backend: a cloth over the adjoint's buffer; implicit Euler, whose adjoint
        // is the CPU's.
        for (o, says) in [
            (SimOptions { n: Some(129), ..opts(Backend::Vulkan, &[]) }, "16384"),
            (opts(Backend::Vulkan, &["integrator=implicit"]), "implicit's adjoint runs on cpu and cpu-par"),
        ] {
            let Some(e) = Sim::open(o).err().map(one_line) else { panic!("a GPU recording ({says}) was not refused") };
            if e.contains("adjoint") {
                assert!(e.contains(says), "{e}");
            } else {
                assert!(std::env::var("CLOTHLAB_REQUIRE_GPU").as_deref() != Ok("1"), "{e}");
            }
        }
        let mut sim = Sim::open(opts(Backend::Cpu, &["strain_iterations=0"])).unwrap();
        assert!(one_line(sim.grab(10, [0.0, 1.0, 0.0]).unwrap_err()).contains("grab"));
        assert!(one_line(sim.substep(3).unwrap_err()).contains("whole frames"));
        sim.step(1).unwrap();
        let np = sim.num_particles();
        let short = vec![[0.0f32; 3]; np - 1];
        assert!(one_line(sim.backward(Some(&short), None).unwrap_err()).contains(&format!("{} rows for {np}", np - 1)));
        let nan = vec![[f32::NAN; 3]; np];
        assert!(one_line(sim.backward(None, Some(&nan)).unwrap_err()).contains("not finite"));
        let mut plain = Sim::open(SimOptions { grad: false, ..opts(Backend::Cpu, &[]) }).unwrap();
        assert!(one_line(plain.backward(None, None).unwrap_err()).contains("grad=True"));
        assert!(plain.recorded().is_none());
    }

    #[test]
    fn a_gpu_sim_s_gradients_are_the_cpu_s_within_f32_rounding() {
        // The default scene without the strain limit, 10 frames: the GPU's adjoint
        // kernels (f32, at the recorded states) against the CPU's f64 model. Their
        // difference is f32 rounding carried back through 80 substeps (the kernels against
        // their twins, with the strain limit too: tests/tests/suite/grad.rs); bound 2e-3 of
        // each gradient (of the largest parameter's for one near 0).
        let set = ["strain_iterations=0"];
        let mut cpu = Sim::open(opts(Backend::Cpu, &set)).unwrap();
        cpu.step(10).unwrap();
        let np = cpu.num_particles();
        let xb: Vec<[f32; 3]> = (0..np).map(|i| [0.0, 1.0 / np as f32, (i % 3) as f32 * 0.1]).collect();
        let want = cpu.backward(Some(&xb), None).unwrap();
        for backend in [Backend::Wgpu, Backend::Vulkan, Backend::Gl] {
            let Some(mut gpu) = super::tests::or_skip(Sim::open(opts(backend, &set))) else { continue };
            gpu.step(10).unwrap();
            let before = gpu.state().unwrap();
            let got = gpu.backward(Some(&xb), None).unwrap();
            assert_eq!(gpu.state().unwrap(), before, "{}: the state is put back", backend.name());
            let scale = want.positions.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
            for (a, b) in got.positions.iter().flatten().zip(want.positions.iter().flatten()) {
                assert!((a - b).abs() <= 2e-3 * scale, "{}: positions {a} vs {b}", backend.name());
            }
            let big = want.params.iter().fold(0.0f64, |m, (_, x)| m.max(x.abs()));
            for ((name, a), (_, b)) in got.params.iter().zip(&want.params) {
                let e = (a - b).abs() / b.abs().max(1e-3 * big);
                assert!(e <= 2e-3, "{}: {name}: {a} vs {b} ({e:.1e})", backend.name());
            }
            assert_eq!(got.pins.len(), 10);
        }
    }

    #[test]
    fn a_recording_of_a_thousand_frames_at_n_128_holds_under_twice_the_state_a_frame() {
        // The default scene at n = 128 on cpu-par, 1 000 frames recorded: the checkpoints
        // are 48 bytes a particle a frame (f64 positions and velocities), 1.5 times the
        // f32 state's 32 — under the bound of twice it; and the process grew by about that
        // (its resident memory: the checkpoints' 786 MB, with 256 MB of slack for what the
        // tests running beside it hold).
        let rss = || -> f64 {
            let s = std::fs::read_to_string("/proc/self/statm").unwrap_or_default();
            let pages: f64 = s.split_whitespace().nth(1).and_then(|p| p.parse().ok()).unwrap_or(0.0);
            pages * 4096.0
        };
        let mut sim = Sim::open(SimOptions { n: Some(128), ..opts(Backend::CpuPar, &[]) }).unwrap();
        let before = rss();
        sim.step(1000).unwrap();
        let grew = rss() - before;
        let (frames, bytes) = sim.recorded().unwrap();
        let state = 32.0 * sim.num_particles() as f64;
        println!(
            "{frames} frames: {:.0} MB recorded ({:.2} × the state a frame); resident memory grew {:.0} MB",
            bytes as f64 / 1e6,
            bytes as f64 / frames as f64 / state,
            grew / 1e6
        );
        assert_eq!(frames, 1000);
        assert!(bytes as f64 <= 2.0 * state * frames as f64, "{bytes} bytes");
        if before > 0.0 {
            assert!(grew < 2.0 * state * frames as f64 + 256e6, "grew {grew} bytes");
        }
    }
}
