//! Why a solver or renderer could not do what it was asked (a leaf module: the grid, the
//! solvers and the backends all return it).

use thiserror::Error;

use crate::params::ParamError;

/// Why a solver could not do what it was asked.
#[derive(Debug, Error)]
pub enum SolverError {
    /// A parameter or scene value was refused.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// A state of another grid size was offered.
    #[error("state is for a {got}×{got} grid, the solver simulates {want}×{want}")]
    GridMismatch {
        /// The solver's n.
        want: u32,
        /// The state's n.
        got: u32,
    },
    /// A kernel's WGSL was refused (a kernel given at run time: the compiler's message).
    #[error("kernel {kernel}: {reason}")]
    Shader {
        /// The shader's name.
        kernel: String,
        /// What the compiler or driver said.
        reason: String,
    },
    /// No GPU adapter, or no Vulkan loader, on this machine (the message says what to
    /// install).
    #[error("{0}")]
    NoAdapter(String),
    /// The grid's spring table is larger than the adapter binds per storage buffer.
    #[error(
        "n = {n} needs a {need_mib} MiB spring table, more than the {limit_mib} MiB this adapter ({adapter}) binds per storage buffer: use n ≤ {max_n} on it"
    )]
    GridTooLarge {
        /// The grid asked for.
        n: u32,
        /// The largest grid the adapter takes.
        max_n: u32,
        /// The table's size, MiB.
        need_mib: u64,
        /// What the adapter binds, MiB.
        limit_mib: u64,
        /// The adapter.
        adapter: String,
    },
    /// The adapter lacks what an option needs (subgroup arithmetic, immediates, …).
    #[error("{0}")]
    Unsupported(String),
    /// A value handed to the solver was refused (a non-finite state, constants or buffers
    /// of another grid, too many colliders).
    #[error("{0}")]
    Invalid(String),
    /// The driver or the API failed (device lost, out of memory, a validation message).
    #[error("{0}")]
    Driver(String),
}

impl SolverError {
    /// [`SolverError::GridTooLarge`] for a table of `per_particle` bytes per particle
    /// against a binding limit of `limit` bytes, or `None` when it fits.
    pub fn check_table(n: u32, per_particle: u64, limit: u64, adapter: &str) -> Result<(), SolverError> {
        let np = n as u64 * n as u64;
        if np * per_particle <= limit {
            return Ok(());
        }
        Err(SolverError::GridTooLarge {
            n,
            max_n: ((limit / per_particle) as f64).sqrt().floor() as u32,
            need_mib: (np * per_particle) >> 20,
            limit_mib: limit >> 20,
            adapter: adapter.to_owned(),
        })
    }
}
