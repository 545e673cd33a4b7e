//! clothlab-wgpu: the cloth solver on wgpu, any [`Variant`] (a set of switches; the
//! presets `naive`, `optimized` and `thesis`, see `clothlab_engine::variant`).
//!
//! Positions and normals live in buffers with `VERTEX | STORAGE` usage so that a renderer
//! can draw them without a copy. Per-kernel GPU times come from timestamp queries where
//! the adapter has them.
//!
//! How it fits: `WgpuEngine` is this API's `clothlab_engine::Engine` (buffers, pipelines
//! from clothlab-shaders' WGSL, dispatches, timestamps); the solver is
//! `GpuSolver<WgpuEngine>`, written once in clothlab-engine. `WgpuRenderer` draws any
//! solver's cloth (shadow map, Blinn-Phong, MSAA, picking), straight from this solver's
//! buffers or from a CPU state uploaded per frame; the app and `clothlab render` use it.
#![forbid(unsafe_code)]

mod context;
pub mod overhead;
mod render;
mod solver;

pub use clothlab_engine::recipe::Variant;
pub use clothlab_engine::{GpuSolver, SolverOptions, VariantSpec};
pub use context::{GpuContext, GpuError, choose_backends, chosen_backends};
pub use render::{ClothSource, WgpuRenderer};
pub use solver::{WgpuEngine, WgpuSolver, wgpu_solver};
