//! Gradients on any kernel runner (docs/gradients.md): a recording
//! ([`clothlab_cpu::grad::Recording`]) walked back by the adjoint kernels
//! ([`crate::kernels::ADJ_INTEGRATE`], [`crate::kernels::ADJ_SPRINGS`]) on a GPU solver or
//! on the CPU engine (their twins). Each frame's substeps are recomputed by the plain
//! kernels from the frame's checkpoint, and each substep's adjoint runs at its input: the
//! strain passes' inputs again, back through each pass last first (`strain_count` at its
//! input, `adj_strain_back`, `adj_strain_gather`), then the force again (`forces`,
//! `springs`), `adj_integrate` and `adj_springs`. The
//! parameters' partials stay in the adjoint's planes, added to by every substep, and are
//! summed once at the end ([`clothlab_cpu::adjoint::partial_sums`]).
//!
//! The states go through the host between substeps (the runner's
//! [`KernelRunner::run_commands`]: uploads, the commands, read-backs): what runs on the
//! GPU is the arithmetic, checked here against the twins and the f64 model; keeping the
//! checkpoints and a ring of substep states on the GPU is what makes it fast (left).

use glam::DVec3;

use clothlab_core::SolverError;
use clothlab_core::grid::{ClothState, ClothTopology, V4};
use clothlab_core::layout::ADJ_ROWS;
use clothlab_core::params::{Integrator, SimParams};
use clothlab_core::scene::Scene;
use clothlab_core::step_params::StepParams;
use clothlab_cpu::grad::{Model, Walk};

use crate::kernels::{self as k, HostBuffers};
use crate::recipe::Command;
use crate::validate::KernelRunner;

/// A recording's walk on `runner`'s kernels ([`Walk`]).
pub struct KernelWalk<'a> {
    runner: &'a mut dyn KernelRunner,
    p: StepParams,
    bufs: HostBuffers,
    /// Each particle's `pos.w`.
    w: Vec<f32>,
    /// The strain limit's passes a substep.
    passes: u32,
}

impl<'a> KernelWalk<'a> {
    /// A walk on `runner` (a solver of `scene` with `params`, or the CPU engine of its
    /// cloth `topo`) of a recording whose particles' `pos.w` are `state`'s. The runner's buffers
    /// are overwritten: a solver's state is the caller's to put back.
    pub fn new(
        runner: &'a mut dyn KernelRunner,
        scene: &Scene,
        params: &SimParams,
        topo: &ClothTopology,
        state: &ClothState,
    ) -> Result<Self, SolverError> {
        if !matches!(params.integrator, Integrator::Verlet | Integrator::SymplecticEuler) {
            return Err(SolverError::Unsupported(format!(
                "the adjoint kernels walk verlet and symplectic-euler, not {} (its adjoint runs on the CPU's f64 model)",
                params.integrator.name()
            )));
        }
        let p = StepParams::new(params, scene, None);
        let np = state.pos.len();
        let mut bufs = HostBuffers::new(state, vec![[0.0; 4]; topo.triangles.len()]);
        bufs.adjoint = vec![[0.0; 4]; ADJ_ROWS as usize * np];
        let w = state.pos.iter().map(|x| x[3]).collect();
        Ok(Self { runner, p, bufs, w, passes: params.strain_iterations })
    }

    fn load(&mut self, x: &[DVec3], v: &[DVec3]) {
        let f = |d: DVec3, w: f32| -> V4 { [d.x as f32, d.y as f32, d.z as f32, w] };
        for (i, (x, v)) in x.iter().zip(v).enumerate() {
            self.bufs.pos[i] = f(*x, self.w[i]);
            self.bufs.vel[i] = f(*v, 0.0);
        }
        self.bufs.pos_out.clone_from(&self.bufs.pos);
    }

    /// Runs `kernels` (each with its clears and swap: `recipe::run`).
    fn run(&mut self, kernels: &[&'static k::KernelDef]) -> Result<(), String> {
        let commands: Vec<Command> = kernels.iter().flat_map(|d| crate::recipe::run(d.plain())).collect();
        self.runner.run_commands(&commands, &self.p, &mut self.bufs).map_err(|e| e.to_string())
    }

    /// The substep's integration and colliders from the loaded state, the force first
    /// (cleared: no wind).
    fn integrate(&mut self) -> Result<(), String> {
        self.bufs.force.iter_mut().for_each(|f| *f = [0.0; 4]);
        self.run(&[&k::FORCES, &k::SPRINGS, &k::INTEGRATE, &k::COLLIDE])
    }

    /// One strain pass (its counts, then the pass and its swap).
    fn strain_pass(&mut self) -> Result<(), String> {
        self.run(&[&k::STRAIN_COUNT, &k::STRAIN_LIMIT])
    }
}

fn d3(v: &V4) -> DVec3 {
    DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64)
}

impl Walk for KernelWalk<'_> {
    fn inputs(&mut self, m: &Model, x: &[DVec3], v: &[DVec3]) -> Result<Vec<(Vec<DVec3>, Vec<DVec3>)>, String> {
        self.load(x, v);
        let mut path = Vec::with_capacity(m.substeps() as usize);
        for _ in 0..m.substeps() {
            path.push((self.bufs.pos.iter().map(d3).collect(), self.bufs.vel.iter().map(d3).collect()));
            self.integrate()?;
            for _ in 0..self.passes {
                self.strain_pass()?;
            }
        }
        Ok(path)
    }

    fn adjoint(
        &mut self,
        _: &Model,
        x: &[DVec3],
        v: &[DVec3],
        xb: &mut [DVec3],
        vb: &mut [DVec3],
        _: &mut [f64],
    ) -> Result<(), String> {
        let np = x.len();
        for (i, (gx, gv)) in xb.iter().zip(vb.iter()).enumerate() {
            self.bufs.adjoint[i] = [gx.x as f32, gx.y as f32, gx.z as f32, 0.0];
            self.bufs.adjoint[np + i] = [gv.x as f32, gv.y as f32, gv.z as f32, 0.0];
        }
        if self.passes > 0 {
            // The strain passes' inputs again, then back through them, last first: each
            // one's counts at its input, then its adjoint's two halves.
            self.load(x, v);
            self.integrate()?;
            let mut inputs = Vec::with_capacity(self.passes as usize);
            for _ in 0..self.passes {
                inputs.push(self.bufs.pos.clone());
                self.strain_pass()?;
            }
            for input in inputs.iter().rev() {
                self.bufs.pos.clone_from(input);
                self.bufs.pos_out.clone_from(input);
                self.run(&[&k::STRAIN_COUNT, &k::ADJ_STRAIN_BACK, &k::ADJ_STRAIN_GATHER])?;
            }
        }
        self.load(x, v);
        self.bufs.force.iter_mut().for_each(|f| *f = [0.0; 4]);
        self.run(&[&k::FORCES, &k::SPRINGS, &k::ADJ_INTEGRATE, &k::ADJ_SPRINGS])?;
        for (i, (gx, gv)) in xb.iter_mut().zip(vb.iter_mut()).enumerate() {
            *gx = d3(&self.bufs.adjoint[i]);
            *gv = d3(&self.bufs.adjoint[np + i]);
        }
        Ok(())
    }

    fn finish(&mut self, m: &Model, params: &mut [f64]) -> Result<(), String> {
        let sums = clothlab_cpu::adjoint::partial_sums(&self.bufs.adjoint, self.w.len());
        for (p, g) in params.iter_mut().zip(m.params_from_partials(&sums)?) {
            *p += g;
        }
        Ok(())
    }
}
