//! [`Sim`]: a scene running on a backend, as a library sees it.

use std::path::Path;

use anyhow::{Context, Result, bail};
use clothlab_core::grid::Grab;
use clothlab_core::{ClothState, ClothTopology, KernelTimings, RenderMode, Scene, SimParams, StateField, View};

use crate::backend::{AnySolver, Backend, GpuSetup, Shared, make};
use crate::record::{MAX_GLB_BYTES, Recording, glb};
use crate::setup::{Physics, Setup, apply_overrides};

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
pub struct Sim {
    solver: AnySolver,
    backend: Backend,
    setup: Setup,
}

impl Sim {
    /// Opens the scene of `opts` on its backend. Every argument is checked first; a GPU
    /// backend without an adapter is refused in one line.
    pub fn open(opts: SimOptions) -> Result<Sim> {
        let setup = opts.physics.setup(opts.n, DEFAULT_N)?;
        let solver = make(opts.backend, setup.scene.clone(), setup.params.clone(), &opts.gpu, &Shared::None)?;
        Ok(Sim { solver, backend: opts.backend, setup })
    }

    /// The backend.
    pub fn backend(&self) -> Backend {
        self.backend
    }

    /// The solver's name (backend and variant, e.g. `vulkan`, `cpu-par`).
    pub fn name(&self) -> &str {
        self.solver.get_ref().name()
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

    /// The parameters in use.
    pub fn params(&self) -> &SimParams {
        self.solver.get_ref().params()
    }

    /// The parameters as `NAME → value` (the names `set` takes).
    pub fn params_json(&self) -> Result<serde_json::Map<String, serde_json::Value>> {
        match serde_json::to_value(self.params())? {
            serde_json::Value::Object(m) => Ok(m),
            _ => bail!("parameters are not an object"),
        }
    }

    /// Replaces the parameters (validated against the cloth first; on error nothing
    /// changes).
    pub fn set_params(&mut self, params: SimParams) -> Result<()> {
        clothlab_core::cloth::check_params(&self.setup.scene, &params)?;
        self.solver.get().set_params(params)?;
        Ok(())
    }

    /// Applies `NAME=VALUE` overrides (as `--set`): every one checked, all or none applied.
    pub fn set(&mut self, sets: &[String]) -> Result<()> {
        let params = apply_overrides(self.params(), sets)?;
        self.set_params(params)
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
        for _ in 0..frames {
            self.solver.get().step_frame()?;
        }
        Ok(())
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
        let whole = self.params().clone();
        if whole.substeps == 1 {
            return self.step(k);
        }
        let single = SimParams { frame_dt: whole.dt(), substeps: 1, ..whole.clone() };
        self.solver.get().set_params(single).context("a frame of one substep")?;
        let stepped = self.step(k);
        self.solver.get().set_params(whole)?;
        stepped
    }

    /// Simulated time, s.
    pub fn time(&self) -> f64 {
        self.solver.get_ref().time()
    }

    /// Sets the simulated time (finite, ≥ 0): moving colliders and pins go where their
    /// motion puts them then.
    pub fn set_time(&mut self, t: f64) -> Result<()> {
        Ok(self.solver.get().set_time(t)?)
    }

    /// A copy of the state (read back from the GPU where it lives there).
    pub fn state(&mut self) -> Result<ClothState> {
        Ok(self.solver.get().state()?)
    }

    /// Replaces the state: of this cloth, finite, or refused with nothing changed.
    pub fn set_state(&mut self, state: &ClothState) -> Result<()> {
        state.check(self.topology())?;
        Ok(self.solver.get().set_state(state)?)
    }

    /// The reference mass inverse masses are relative to, kg (the cloth's mass over its
    /// particles).
    fn reference_mass(&self) -> f32 {
        self.params().cloth_mass / self.num_particles().max(1) as f32
    }

    /// One array of the state as it is (w: see [`ClothState`]), read back alone.
    pub fn field(&mut self, field: StateField) -> Result<Vec<[f32; 4]>> {
        Ok(self.solver.get().field(field)?)
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

    /// Sets the positions, one per particle, finite (inverse masses kept).
    pub fn set_positions(&mut self, x: &[[f32; 3]]) -> Result<()> {
        let mut s = self.state()?;
        put_xyz(&mut s.pos, x, "positions")?;
        self.set_state(&s)
    }

    /// Sets the velocities, one per particle, finite.
    pub fn set_velocities(&mut self, v: &[[f32; 3]]) -> Result<()> {
        let mut s = self.state()?;
        put_xyz(&mut s.vel, v, "velocities")?;
        self.set_state(&s)
    }

    /// Sets the inverse masses, 1/kg: one per particle, finite and ≥ 0 (0 pins it).
    pub fn set_inverse_masses(&mut self, w: &[f32]) -> Result<()> {
        let mut s = self.state()?;
        if w.len() != s.pos.len() {
            bail!("inverse masses: {} values for {} particles", w.len(), s.pos.len());
        }
        if let Some((i, v)) = w.iter().enumerate().find(|(_, v)| !(v.is_finite() && **v >= 0.0)) {
            bail!("inverse masses: particle {i} has {v}; an inverse mass is finite and ≥ 0");
        }
        let m = self.reference_mass();
        for (p, &inv) in s.pos.iter_mut().zip(w) {
            p[3] = inv * m;
        }
        self.set_state(&s)
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
    pub fn grab(&mut self, particle: u32, target: [f32; 3]) -> Result<()> {
        let np = self.num_particles();
        if particle as usize >= np {
            bail!("particle {particle}: the cloth has {np} particles (0 ..= {})", np.saturating_sub(1));
        }
        if !target.iter().all(|v| v.is_finite()) {
            bail!("grab target {target:?}: a position is finite");
        }
        self.solver.get().set_grab(Some(Grab { particle, target }));
        Ok(())
    }

    /// Lets go of the grabbed particle.
    pub fn release(&mut self) {
        self.solver.get().set_grab(None);
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
    pub fn crossings(&mut self) -> Result<usize> {
        Ok(clothlab_core::crossings::count(&self.field(StateField::Pos)?, &self.topology().triangles).pairs)
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

    /// Runs `frames` frames recording every `every`-th (and the first) and writes them to
    /// `path` as binary glTF (as `sim --record`); returns the frames kept.
    pub fn record(&mut self, path: &Path, frames: u64, every: u32) -> Result<usize> {
        if !path.extension().is_some_and(|e| e.eq_ignore_ascii_case("glb")) {
            bail!("record {}: a recording is binary glTF, give a .glb file name", path.display());
        }
        if !(1..=1_000_000).contains(&every) {
            bail!("invalid every {every}: must be in 1 ..= 1000000");
        }
        if frames > MAX_STEPS {
            bail!("invalid frames {frames}: must be in 0 ..= {MAX_STEPS}");
        }
        crate::files::check_writable(path)?;
        let kept = 1 + frames / u64::from(every);
        let np = self.num_particles() as u64;
        let bytes = Recording::predicted_bytes(kept, np, self.topology().triangles.len() as u64);
        if bytes > MAX_GLB_BYTES {
            bail!(
                "record: {kept} frames of {np} particles would be {bytes} bytes, more than the {MAX_GLB_BYTES} a .glb may hold; record every more frames"
            );
        }
        let t0 = self.time() as f32;
        let mut recording = Recording::default();
        recording.push(0.0, &self.state()?);
        for f in 1..=frames {
            self.solver.get().step_frame()?;
            if f % u64::from(every) == 0 {
                recording.push(self.time() as f32 - t0, &self.state()?);
            }
        }
        let bytes = glb(&recording, self.topology(), &self.setup.scene)?;
        crate::files::write_bytes(path, &bytes)?;
        Ok(recording.frames.len())
    }

    /// The solver, for what the facade does not wrap (its kernels, its buffers).
    pub fn solver(&mut self) -> &mut AnySolver {
        &mut self.solver
    }
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
