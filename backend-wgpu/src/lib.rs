//! clothlab-wgpu: the cloth solver on wgpu, any [`Variant`] (a set of switches; the
//! presets `naive`, `optimized` and `thesis`, see `clothlab_engine::variant`).
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
pub use clothlab_engine::{GpuSolver, SolverOptions, VariantSpec};
pub use context::{GpuContext, GpuError};
pub use render::{ClothSource, WgpuRenderer};
pub use solver::{WgpuEngine, WgpuSolver, wgpu_solver};
