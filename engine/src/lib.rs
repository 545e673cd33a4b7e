//! clothlab-engine: the step as data, shared by every backend.
//!
//! * [`kernels`] — the kernel registry: one row per kernel (WGSL, CPU twin, what it runs
//!   over, bindings read and written, pure outputs, bound, label, variants);
//! * [`variant`] — variants as sets of switches (every one with its values in
//!   [`variant::SWITCHES`]) and the presets `naive`, `optimized`, `thesis`;
//! * [`recipe`] — the commands of a substep per variant (dispatches, clears, swaps) and
//!   the barriers they need;
//! * [`cpu`] — the CPU engine: runs any commands through the twins;
//! * [`grad`] — gradients: a recording walked back by the adjoint kernels on any runner;
//! * [`gpu`] — the [`Engine`] trait: the API's part of a GPU solver (buffers, uploads,
//!   downloads, dispatches, barriers, timestamps, submit and wait);
//! * [`solver`] — [`GpuSolver`]: `Solver` and `KernelRunner` written once over any engine;
//! * [`validate`] — every kernel of a GPU runner against its twin, and the bisection of a
//!   rollout between the CPU engine and a GPU backend;
//! * [`tables`] — the spring tables as the GPU backends upload them, and their timing;
//! * [`worlds`] — a batch of worlds in one set of buffers, every kernel dispatched once
//!   for all of them ([`Batch`]).
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod cpu;
pub mod gpu;
pub mod grad;
pub mod kernels;
pub mod recipe;
pub mod solver;
pub mod tables;
pub mod validate;
pub mod variant;
pub mod worlds;

pub use cpu::{CpuEngine, RecipeSolver};
pub use gpu::Engine;
pub use kernels::{Flavor, HostBuffers, KernelDef, KernelRef, TwinArgs};
pub use recipe::{Caps, Command, StatsMode, Variant};
pub use solver::{Batch, GpuSolver, SolverOptions};
pub use validate::KernelRunner;
pub use variant::{VariantError, VariantSpec};

use clothlab_core::SolverError;

/// Why the engine could not do what it was asked.
#[derive(Debug, thiserror::Error)]
pub enum EngineError {
    /// A kernel's WGSL did not compile (a kernel from outside: its own error).
    #[error("kernel {kernel}: {reason}")]
    Shader {
        /// The shader's name.
        kernel: String,
        /// What naga or the driver said.
        reason: String,
    },
}

impl From<EngineError> for SolverError {
    fn from(e: EngineError) -> Self {
        match e {
            EngineError::Shader { kernel, reason } => SolverError::Shader { kernel, reason },
        }
    }
}
