//! clothlab-wgpu: the cloth solver on wgpu, in the two variants of DESIGN.md.
//!
//! * [`Variant::Naive`] — the direct port: one dispatch per kernel of the step, spring
//!   forces scattered per spring and vertex normals per triangle with compare-exchange
//!   atomics, one submission per substep.
//! * [`Variant::Optimized`] — `forces` fused into the spring gather and `integrate` with
//!   `collide`, springs read from the read-only spring table, normals gathered from face
//!   normals (no atomics), every substep of a frame in one encoder and one submission.
//!
//! Positions and normals live in buffers with `VERTEX | STORAGE` usage so that a renderer
//! can draw them without a copy. Per-kernel GPU times come from timestamp queries where
//! the adapter has them.
#![forbid(unsafe_code)]

mod context;
pub mod overhead;
mod render;
mod solver;

pub use clothlab_engine::recipe::Variant;
pub use clothlab_engine::{GpuSolver, SolverOptions, SpringTable};
pub use context::{GpuContext, GpuError};
pub use render::{ClothSource, WgpuRenderer};
pub use solver::{WgpuEngine, WgpuSolver, wgpu_solver};
