//! The simulation the window shows: a solver of any backend, its scene and parameters, the
//! grabbed particle, and the timing history the chart draws.

use std::collections::VecDeque;

use anyhow::{Context, Result};
use clothlab_core::grid::{ClothState, Grab};
use clothlab_core::timing::{CPU_RECORD, CPU_SUBMIT, FRAME, SUBSTEP};
use clothlab_core::{CpuSolver, Exec, Scene, SimParams, Solver};
use clothlab_vulkan::raw::Device;
use clothlab_vulkan::{VkCloth, VulkanOptions, VulkanSolver};
use clothlab_wgpu::{ClothSource, GpuContext, Variant, WgpuSolver};

use crate::cli::Backend;

/// Frames of timing history the chart shows.
pub const HISTORY: usize = 240;

/// The device a GPU solver must share with the window's renderer.
pub enum Shared<'a> {
    /// The window draws through wgpu on this context.
    Wgpu(&'a GpuContext),
    /// The window draws through raw Vulkan on this device.
    Vulkan(&'a std::sync::Arc<Device>),
    /// No window: every GPU solver opens its own device.
    #[cfg_attr(not(test), allow(dead_code))]
    None,
}

/// A solver of any backend, kept by type so that a GPU solver on the window's device can
/// hand its buffers to the renderer.
pub enum AnySolver {
    /// Serial or rayon.
    Cpu(Box<CpuSolver>),
    /// wgpu; `true` when on the window's context.
    Wgpu(Box<WgpuSolver>, bool),
    /// Raw Vulkan; `true` when on the window's device.
    Vulkan(Box<VulkanSolver>, bool),
}

impl AnySolver {
    /// The solver.
    pub fn get(&mut self) -> &mut dyn Solver {
        match self {
            AnySolver::Cpu(s) => s.as_mut(),
            AnySolver::Wgpu(s, _) => s.as_mut(),
            AnySolver::Vulkan(s, _) => s.as_mut(),
        }
    }

    /// The solver, read only.
    pub fn get_ref(&self) -> &dyn Solver {
        match self {
            AnySolver::Cpu(s) => s.as_ref(),
            AnySolver::Wgpu(s, _) => s.as_ref(),
            AnySolver::Vulkan(s, _) => s.as_ref(),
        }
    }
}

/// The cloth as the wgpu renderer takes it: the solver's buffers when it is a wgpu solver
/// on the window's context, else a state (`copy` holds a read-back one).
pub fn wgpu_cloth<'a>(solver: &'a mut AnySolver, copy: &'a mut Option<ClothState>) -> Result<ClothSource<'a>> {
    Ok(match solver {
        AnySolver::Wgpu(s, true) => {
            let (pos, normal) = s.vertex_buffers();
            ClothSource::Gpu { pos, normal }
        }
        AnySolver::Cpu(s) => ClothSource::Cpu(s.state_ref()),
        other => ClothSource::Cpu(copy.insert(other.get().state()?)),
    })
}

/// The cloth as the Vulkan renderer takes it (see [`wgpu_cloth`]).
pub fn vulkan_cloth<'a>(solver: &'a mut AnySolver, copy: &'a mut Option<ClothState>) -> Result<VkCloth<'a>> {
    Ok(match solver {
        AnySolver::Vulkan(s, true) => {
            let (pos, normal) = s.vertex_buffers();
            VkCloth::Gpu { pos, normal }
        }
        AnySolver::Cpu(s) => VkCloth::Cpu(s.state_ref()),
        other => VkCloth::Cpu(copy.insert(other.get().state()?)),
    })
}

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
}

/// Makes a solver of `backend` on the window's device where it is a GPU solver of the
/// window's API, else on its own (drawn through a CPU copy).
pub fn make_solver(backend: Backend, scene: Scene, params: SimParams, shared: &Shared<'_>) -> Result<AnySolver> {
    let optimized = matches!(backend, Backend::Wgpu | Backend::Vulkan);
    let v = if optimized { Variant::Optimized } else { Variant::Naive };
    Ok(match (backend, shared) {
        (Backend::Cpu, _) => AnySolver::Cpu(Box::new(CpuSolver::new(Exec::Serial, scene, params)?)),
        (Backend::CpuPar, _) => AnySolver::Cpu(Box::new(CpuSolver::new(Exec::Parallel, scene, params)?)),
        (Backend::WgpuNaive | Backend::Wgpu, Shared::Wgpu(ctx)) => {
            AnySolver::Wgpu(Box::new(WgpuSolver::with_context((*ctx).clone(), v, scene, params)?), true)
        }
        (Backend::WgpuNaive | Backend::Wgpu, Shared::Vulkan(_) | Shared::None) => {
            AnySolver::Wgpu(Box::new(WgpuSolver::new(v, scene, params)?), false)
        }
        (Backend::VulkanNaive | Backend::Vulkan, Shared::Vulkan(dev)) => AnySolver::Vulkan(
            Box::new(VulkanSolver::on_device((*dev).clone(), v, scene, params, VulkanOptions::default())?),
            true,
        ),
        (Backend::VulkanNaive | Backend::Vulkan, Shared::Wgpu(_) | Shared::None) => {
            let options = VulkanOptions { validation: crate::cli::vulkan_validation(), ..Default::default() };
            AnySolver::Vulkan(Box::new(VulkanSolver::with_options(v, scene, params, options)?), false)
        }
    })
}

impl Sim {
    /// A fresh cloth of `n × n` on `backend`.
    pub fn new(backend: Backend, n: u32, params: SimParams, shared: &Shared<'_>) -> Result<Self> {
        let scene = Scene::with_n(n);
        scene.validate()?;
        let solver = make_solver(backend, scene, params, shared).context("starting the solver")?;
        Ok(Self { backend, solver, grab: None, history: VecDeque::new(), frames: 0 })
    }

    /// Advances one frame and records its timings.
    pub fn step(&mut self) -> Result<()> {
        let grab = self.grab;
        let solver = self.solver.get();
        solver.set_grab(grab);
        solver.step_frame()?;
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

    /// The last substep time, ns.
    pub fn substep_ns(&self) -> Option<f64> {
        self.history.back()?.iter().find(|(l, _)| l == SUBSTEP).map(|(_, v)| *v)
    }

    /// Switches to `backend`, keeping the cloth where it is.
    pub fn switch(&mut self, backend: Backend, shared: &Shared<'_>) -> Result<()> {
        let old = self.solver.get();
        let state: ClothState = old.state()?;
        let mut solver = make_solver(backend, old.scene().clone(), old.params().clone(), shared)?;
        solver.get().set_state(&state)?;
        self.solver = solver;
        self.backend = backend;
        self.history.clear();
        Ok(())
    }

    /// A new cloth of `n × n` (or the same size: a reset), on the same backend and
    /// parameters.
    pub fn regrid(&mut self, n: u32, shared: &Shared<'_>) -> Result<()> {
        let params = self.solver.get_ref().params().clone();
        *self = Self::new(self.backend, n, params, shared)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn switching_the_solver_keeps_the_cloth_where_it_is() {
        let mut sim = Sim::new(Backend::Cpu, 24, SimParams::default(), &Shared::None).unwrap();
        for _ in 0..6 {
            sim.step().unwrap();
        }
        let before = sim.solver.get().state().unwrap();
        let mut targets = vec![Backend::CpuPar];
        // GPU solvers where an adapter must be (lavapipe in CI).
        if std::env::var("CLOTHLAB_REQUIRE_GPU").as_deref() == Ok("1") {
            targets.extend([Backend::Wgpu, Backend::Vulkan, Backend::Cpu]);
        }
        for b in targets {
            sim.switch(b, &Shared::None).unwrap();
            assert_eq!(sim.backend, b);
            let after = sim.solver.get().state().unwrap();
            // The state is copied, not re-simulated: bit for bit.
            assert_eq!(before.pos, after.pos, "{b:?}");
            assert_eq!(before.prev, after.prev, "{b:?}");
        }
        // And it simulates on from there: one more frame moves the cloth a little.
        sim.step().unwrap();
        let next = sim.solver.get().state().unwrap();
        let moved = next.pos.iter().zip(&before.pos).map(|(a, b)| (a[1] - b[1]).abs()).fold(0.0f32, f32::max);
        assert!(moved > 0.0 && moved < 0.1, "one frame moves the cloth by {moved} m");
    }
}
