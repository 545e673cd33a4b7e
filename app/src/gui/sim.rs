//! The simulation the window shows: a solver of any backend, its scene and parameters, the
//! grabbed particle, and the timing history the chart draws.

use std::collections::VecDeque;

use anyhow::{Context, Result};
use clothlab::core::grid::{ClothState, Grab};
use clothlab::core::timing::{CPU_RECORD, CPU_SUBMIT, FRAME, SUBSTEP};
use clothlab::core::{Scene, SimParams};

use clothlab::engine::{Variant, VariantSpec};

use clothlab::backend::{AnySolver, Backend, GpuSetup, Shared, make};

/// Frames of timing history the chart shows.
pub const HISTORY: usize = 240;

/// A running simulation.
pub struct Sim {
    /// Which solver runs.
    pub backend: Backend,
    /// The solver.
    pub solver: AnySolver,
    /// The grabbed particle and where it was when grabbed.
    pub grab: Option<Grab>,
    /// Per frame: (substep median ns, per-kernel medians ns) of the last frames.
    pub history: VecDeque<Vec<(String, f64)>>,
    /// Frames simulated since the last reset.
    pub frames: u64,
    /// Wall time of the last frame's simulation per substep, ns: from the call to the
    /// solver's return, which for a GPU solver timing its kernels is after its fence.
    pub wall_substep_ns: Option<f64>,
}

/// The substep time the app shows: the GPU's (timestamps) where it agrees with the wall
/// clock, else the wall clock's, saying why.
#[derive(Debug, Clone, PartialEq)]
pub enum SubstepTime {
    /// GPU timestamps (or the CPU solver's own clock), ns.
    Measured(f64),
    /// Fence to fence over the frame, ns, because the timestamps (ns) cannot be true.
    Wall {
        /// Wall time per substep.
        wall: f64,
        /// What the timestamps said.
        timestamps: f64,
    },
    /// Fence to fence over the frame, ns, because the adapter's timestamps came back as
    /// (next to) zero (llvmpipe's OpenGL in a window's context: under 5 µs of a 0.84 ms
    /// substep at n = 64): it gives no kernel timings.
    NoTimestamps {
        /// Wall time per substep.
        wall: f64,
    },
}

/// Whether timestamps saying `gpu` ns per substep can be true of a frame that took `wall`
/// ns per substep from submission to fence. The GPU cannot take longer than the wall
/// (5 % for clock granularity); nor much less — under 60 % — once a substep is long
/// enough that recording and submitting cannot explain the gap (on lavapipe, once the
/// device has drawn, the timestamps stop bracketing the dispatches: measured at n = 128,
/// Vulkan's said 0.09 ms and wgpu's 1.55 ms against 3.1–3.3 ms per substep, which `sim`
/// confirms on an undrawn device). Below 0.125 ms per substep (2 ms a frame of 16) the
/// wall is mostly the submission's fixed cost, and the timestamps are believed.
pub fn substep_time(gpu: f64, wall: f64) -> SubstepTime {
    // The queries read (next to) zero — under 1 % of the wall, where a real GPU's
    // timestamps of a substep are tens of per cent of it even when launches dominate:
    // no timings at all, not wrong ones.
    if gpu < 0.01 * wall {
        return SubstepTime::NoTimestamps { wall };
    }
    let plausible = gpu <= 1.05 * wall && (gpu >= 0.6 * wall || wall < 125_000.0);
    if plausible { SubstepTime::Measured(gpu) } else { SubstepTime::Wall { wall, timestamps: gpu } }
}

impl Sim {
    /// A fresh cloth of `scene` on `backend`.
    pub fn new(backend: Backend, scene: Scene, params: SimParams, shared: &Shared<'_>) -> Result<Self> {
        scene.validate()?;
        let solver = make(backend, scene, params, &GpuSetup::default(), shared).context("starting the solver")?;
        Ok(Self { backend, solver, grab: None, history: VecDeque::new(), frames: 0, wall_substep_ns: None })
    }

    /// Advances one frame and records its timings.
    pub fn step(&mut self) -> Result<()> {
        let grab = self.grab;
        let solver = self.solver.get();
        solver.set_grab(grab);
        let t0 = std::time::Instant::now();
        solver.step_frame()?;
        self.wall_substep_ns = Some(t0.elapsed().as_nanos() as f64 / solver.params().substeps as f64);
        self.frames += 1;
        let t = solver.timings();
        let row: Vec<(String, f64)> = t
            .rows
            .iter()
            .filter(|r| r.label != FRAME && r.label != CPU_RECORD && r.label != CPU_SUBMIT)
            .map(|r| (r.label.clone(), r.median_ns))
            .collect();
        solver.reset_timings();
        // The first frames on a new solver include pipeline compilation: not in the chart.
        if !row.is_empty() && self.frames > 3 {
            self.history.push_back(row);
            while self.history.len() > HISTORY {
                self.history.pop_front();
            }
        }
        Ok(())
    }

    /// The last substep time, ns, as the solver measured it.
    pub fn substep_ns(&self) -> Option<f64> {
        self.history.back()?.iter().find(|(l, _)| l == SUBSTEP).map(|(_, v)| *v)
    }

    /// The last substep time to show: the solver's where the wall clock agrees.
    pub fn substep_time(&self) -> Option<SubstepTime> {
        let measured = self.substep_ns()?;
        Some(match self.wall_substep_ns {
            Some(wall) => substep_time(measured, wall),
            None => SubstepTime::Measured(measured),
        })
    }

    /// Switches to `backend` (its preset), keeping the cloth where it is.
    pub fn switch(&mut self, backend: Backend, shared: &Shared<'_>) -> Result<()> {
        self.rebuild(backend, &GpuSetup::default(), shared)
    }

    /// Runs variant `v` on the same GPU backend, keeping the cloth where it is; a switch
    /// the adapter lacks is refused and the running solver kept.
    pub fn set_variant(&mut self, v: Variant, shared: &Shared<'_>) -> Result<()> {
        let setup = GpuSetup { variant: Some(VariantSpec::exact(v)), ..GpuSetup::default() };
        self.rebuild(self.backend, &setup, shared)
    }

    /// New colliders (and floor) under the same cloth, which stays where it is; a scene
    /// with another cloth is refused (that is a new cloth: [`Sim::new`]).
    pub fn set_scene(&mut self, scene: Scene, shared: &Shared<'_>) -> Result<()> {
        scene.validate()?;
        if scene.cloth != self.solver.get_ref().scene().cloth {
            anyhow::bail!("the colliders change under the same cloth; a new cloth is a new simulation");
        }
        let variant = self.solver.variant();
        let setup = GpuSetup { variant: variant.map(VariantSpec::exact), ..GpuSetup::default() };
        self.rebuild_with(self.backend, scene, &setup, shared)
    }

    /// Moves the cloth onto a new solver of `backend` set up as `setup`.
    fn rebuild(&mut self, backend: Backend, setup: &GpuSetup, shared: &Shared<'_>) -> Result<()> {
        let scene = self.solver.get_ref().scene().clone();
        self.rebuild_with(backend, scene, setup, shared)
    }

    /// Moves the cloth onto a new solver of `backend` for `scene`, set up as `setup`.
    fn rebuild_with(&mut self, backend: Backend, scene: Scene, setup: &GpuSetup, shared: &Shared<'_>) -> Result<()> {
        let old = self.solver.get();
        let state: ClothState = old.state()?;
        let time = old.time();
        let mut solver = make(backend, scene, old.params().clone(), setup, shared)?;
        solver.get().set_state(&state)?;
        solver.get().set_time(time)?;
        self.solver = solver;
        self.backend = backend;
        self.history.clear();
        Ok(())
    }

    /// A new cloth of `n × n` (or the same size: a reset) in the same scene, on the same
    /// backend and parameters.
    /// A self-collision thickness above the new grid's bound is brought down to it.
    pub fn regrid(&mut self, n: u32, shared: &Shared<'_>) -> Result<()> {
        let mut params = self.solver.get_ref().params().clone();
        let mut scene = self.solver.get_ref().scene().clone();
        scene.cloth.n = n;
        if params.self_collision.on() && !scene.cloth.is_mesh() {
            let spacing = scene.cloth.size / (n.max(2) - 1) as f32;
            let max = SimParams::max_thickness_on_grid(params.self_collision, spacing);
            params.self_thickness = params.self_thickness.min(max);
        }
        *self = Self::new(self.backend, scene, params, shared)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn timestamps_that_cannot_be_true_give_way_to_the_wall_clock() {
        // lavapipe after drawing, n = 128: 0.09 (Vulkan) and 1.55 ms (wgpu) of timestamps
        // in a 3.3 ms substep.
        assert_eq!(substep_time(90e3, 3.3e6), SubstepTime::Wall { wall: 3.3e6, timestamps: 90e3 });
        assert!(matches!(substep_time(1.55e6, 3.3e6), SubstepTime::Wall { .. }));
        // A real GPU's long substep: timestamps a little under the wall.
        assert_eq!(substep_time(2.8e6, 3e6), SubstepTime::Measured(2.8e6));
        // Longer than the wall: impossible.
        assert!(matches!(substep_time(4e6, 3e6), SubstepTime::Wall { .. }));
        // Short substeps: the wall is the submission's fixed cost, the timestamps stand.
        assert_eq!(substep_time(5e3, 100e3), SubstepTime::Measured(5e3));
        // llvmpipe's GL in the app's window: the timestamps read (next to) zero. No
        // timings, said so.
        assert_eq!(substep_time(0.0, 3e6), SubstepTime::NoTimestamps { wall: 3e6 });
        assert_eq!(substep_time(4e3, 0.84e6), SubstepTime::NoTimestamps { wall: 0.84e6 });
    }

    use super::*;

    #[test]
    fn switching_the_solver_keeps_the_cloth_where_it_is() {
        let mut sim = Sim::new(Backend::Cpu, Scene::with_n(24), SimParams::default(), &Shared::None).unwrap();
        for _ in 0..6 {
            sim.step().unwrap();
        }
        let before = sim.solver.get().state().unwrap();
        let mut targets = vec![Backend::CpuPar];
        // GPU solvers where an adapter must be (lavapipe in CI).
        if std::env::var("CLOTHLAB_REQUIRE_GPU").as_deref() == Ok("1") {
            targets.extend([Backend::Wgpu, Backend::Vulkan, Backend::Gl, Backend::Cpu]);
        }
        for b in targets {
            sim.switch(b, &Shared::None).unwrap();
            assert_eq!(sim.backend, b);
            let after = sim.solver.get().state().unwrap();
            // The state is copied, not re-simulated: bit for bit.
            assert_eq!(before.pos, after.pos, "{b:?}");
            assert_eq!(before.vel, after.vel, "{b:?}");
        }
        // And it simulates on from there: one more frame moves the cloth a little.
        sim.step().unwrap();
        let next = sim.solver.get().state().unwrap();
        let moved = next.pos.iter().zip(&before.pos).map(|(a, b)| (a[1] - b[1]).abs()).fold(0.0f32, f32::max);
        assert!(moved > 0.0 && moved < 0.1, "one frame moves the cloth by {moved} m");
    }

    #[test]
    fn new_colliders_go_under_the_running_cloth_and_another_cloth_is_refused() {
        let mut sim = Sim::new(Backend::Cpu, Scene::with_n(16), SimParams::default(), &Shared::None).unwrap();
        for _ in 0..4 {
            sim.step().unwrap();
        }
        let before = sim.solver.get().state().unwrap();
        let mut scene = sim.solver.get_ref().scene().clone();
        scene.spheres.clear();
        scene.boxes.push(clothlab::core::Aabb::new([-0.5, 0.0, -0.5], [0.5, 0.6, 0.5]));
        sim.set_scene(scene.clone(), &Shared::None).unwrap();
        assert_eq!(sim.solver.get_ref().scene(), &scene);
        // The cloth is moved, not rebuilt: bit for bit where it was.
        assert_eq!(sim.solver.get().state().unwrap().pos, before.pos);
        // A scene with another cloth is a new simulation, not new colliders.
        let mut other = scene.clone();
        other.cloth.n = 20;
        let e = sim.set_scene(other, &Shared::None).unwrap_err();
        assert!(e.to_string().contains("new cloth"), "{e}");
        assert_eq!(sim.solver.get_ref().scene(), &scene);
    }
}
