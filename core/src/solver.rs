//! The `Solver` and `Renderer` traits every backend implements.

use thiserror::Error;

use crate::camera::OrbitCamera;
pub use crate::error::SolverError;
use crate::grid::{ClothState, Grab};
use crate::params::SimParams;
use crate::scene::Scene;
use crate::stats::SubstepStats;
use crate::timing::KernelTimings;

/// `t` as a simulated time: finite and ≥ 0 (see [`Solver::set_time`]).
pub fn checked_time(t: f64) -> Result<f64, SolverError> {
    if t.is_finite() && t >= 0.0 {
        Ok(t)
    } else {
        Err(SolverError::Invalid(format!("a simulated time is finite and ≥ 0 s, not {t}")))
    }
}

/// One array of a solver's state (see [`Solver::field`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StateField {
    /// Positions; w the relative inverse mass.
    Pos,
    /// Velocities.
    Vel,
    /// The force accumulator.
    Force,
    /// Vertex normals.
    Normal,
}

/// What the contact between triangles did in a solver's last substep (see
/// [`Solver::contact_stats`]; `core::tri_contact::Contact`'s counts).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ContactStats {
    /// How far the pair search looked, m.
    pub reach: f32,
    /// Pairs (vertex–triangle and edge–edge) within the reach at the substep's start.
    pub pairs: usize,
    /// Searches for pairs since the solver was built (the pairs a search finds within its
    /// reach and a margin serve the substeps after it until some vertex has moved too far:
    /// docs/contact.md).
    pub searches: u64,
    /// Partial searches since the solver was built: the pairs of the primitives of the
    /// vertices that moved too far, found again (the rest still held).
    pub refreshes: u64,
    /// Pairs the last search kept (within its reach and margin), which each substep's
    /// pairs are filtered from.
    pub kept: usize,
    /// Pairs whose approach the velocity pass slowed.
    pub slowed: usize,
    /// Pair pushes of the separation (summed over its passes, and over XPBD's iterations
    /// where each takes one).
    pub pushed: usize,
    /// Vertices whose motion the bound cut short.
    pub clamped: usize,
    /// How far the cloths moved as one in the last substep, m: their mean displacement
    /// where no vertex moved farther from it than its bound but some moved farther than
    /// it from rest (measured from the mean, nothing was cut), else 0
    /// (`core::tri_contact::Contact::clamp`).
    pub shared: f32,
}

impl ContactStats {
    /// What the contact did, without how its pairs were found (`searches`, `refreshes`
    /// and `kept` cleared): those differ between backends and margins, the pairs and so
    /// the rest do not — what the bit-identity tests compare.
    pub fn outcome(self) -> Self {
        Self { searches: 0, refreshes: 0, kept: 0, ..self }
    }
}

/// A cloth simulation on some backend.
pub trait Solver {
    /// Short name of the backend and variant, e.g. `cpu`, `cpu-par`.
    fn name(&self) -> &str;
    /// The scene being simulated.
    fn scene(&self) -> &Scene;
    /// The parameters in use.
    fn params(&self) -> &SimParams;
    /// Replaces the parameters (validated first; on error nothing changes).
    fn set_params(&mut self, params: SimParams) -> Result<(), SolverError>;
    /// Starts, moves or (with `None`) ends a mouse drag.
    fn set_grab(&mut self, grab: Option<Grab>);
    /// Advances one frame: `params().substeps` substeps.
    fn step_frame(&mut self) -> Result<(), SolverError>;
    /// A copy of the current state (read back from the GPU where it lives there).
    fn state(&mut self) -> Result<ClothState, SolverError>;
    /// One array of the state, without the others: a GPU solver reads back that buffer
    /// alone (a script reading positions every frame pays for one buffer, not four).
    fn field(&mut self, field: StateField) -> Result<Vec<crate::grid::V4>, SolverError> {
        let s = self.state()?;
        Ok(match field {
            StateField::Pos => s.pos,
            StateField::Vel => s.vel,
            StateField::Force => s.force,
            StateField::Normal => s.normal,
        })
    }
    /// Replaces the current state, e.g. when switching backends mid-run.
    fn set_state(&mut self, state: &ClothState) -> Result<(), SolverError>;
    /// Simulated time, s: the sum of the substeps run (moving colliders are where their
    /// motion puts them at this time; `crate::motion`).
    fn time(&self) -> f64;
    /// Sets the simulated time (switching backends mid-run carries it over; a finite
    /// time ≥ 0, else refused).
    fn set_time(&mut self, t: f64) -> Result<(), SolverError>;
    /// Per-kernel timings since the last reset.
    fn timings(&self) -> KernelTimings;
    /// Forgets the recorded timings.
    fn reset_timings(&mut self);
    /// Turns per-kernel timing on (the default) or off. GPU solvers write timestamps
    /// around every dispatch and read them back each frame while it is on; `clothlab bench`
    /// turns it off to time whole frames without that cost. CPU solvers ignore it.
    fn set_kernel_timing(&mut self, _on: bool) {}
    /// The contact between triangles' counts in the last substep, where the solver runs
    /// it (the CPU solvers with `self_collision = "triangles"`); `None` otherwise.
    fn contact_stats(&self) -> Option<ContactStats> {
        None
    }
    /// Statistics of every substep of the last frame, where the solver computes them on
    /// the way (the Vulkan solver with statistics on); empty otherwise.
    fn substep_stats(&self) -> Vec<SubstepStats> {
        Vec::new()
    }
    /// Gives `[[pins]]` group `group` — one the scene marks `scripted` — a new motion,
    /// which its pins follow from the next substep (`crate::pins::set_scripted`).
    fn set_pin_motion(&mut self, group: usize, motion: crate::motion::Motion) -> Result<(), SolverError>;
}

/// How the cloth is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum RenderMode {
    /// One point per particle.
    Points,
    /// The triangle edges.
    Lines,
    /// Lit, textured triangles.
    #[default]
    Triangles,
}

/// What a frame shows, apart from the cloth itself.
#[derive(Debug, Clone, PartialEq)]
pub struct View {
    /// The camera.
    pub camera: OrbitCamera,
    /// Point light position, m.
    pub light: [f32; 3],
    /// Cloth render mode.
    pub mode: RenderMode,
}

/// Why a renderer could not draw.
#[derive(Debug, Error)]
pub enum RenderError {
    /// A target size of zero or beyond the device's limits.
    #[error("invalid target size {width}×{height}: {reason}")]
    InvalidSize {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
        /// What is allowed.
        reason: String,
    },
    /// The backend failed.
    #[error("{0}")]
    Backend(String),
}

/// Draws the scene and the cloth (implemented by the GPU backends). The device and the
/// cloth's buffers are the API's own types, hence the associated types.
pub trait Renderer {
    /// What the renderer draws with (a wgpu device and queue, a Vulkan device, …).
    type Context;
    /// Where the cloth's positions and normals come from for one frame.
    type Cloth<'a>;
    /// Changes the size of the render target; a refused size changes nothing.
    fn resize(&mut self, ctx: &Self::Context, width: u32, height: u32) -> Result<(), RenderError>;
    /// Draws one frame of the scene.
    fn render(&mut self, ctx: &Self::Context, view: &View, cloth: Self::Cloth<'_>) -> Result<(), RenderError>;
    /// The particle drawn at pixel `(x, y)` (origin top left), if any.
    fn pick(
        &mut self,
        ctx: &Self::Context,
        view: &View,
        cloth: Self::Cloth<'_>,
        x: u32,
        y: u32,
    ) -> Result<Option<u32>, RenderError>;
    /// The last frame as tightly packed sRGB RGBA8 rows.
    fn read_image(&self, ctx: &Self::Context) -> Result<Vec<u8>, RenderError>;
}
