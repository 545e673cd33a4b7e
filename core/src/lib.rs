//! clothlab-core: the cloth model, its parameters and scene, and the CPU reference.
//!
//! Nothing here touches a GPU. The GPU backends implement the same [`Solver`] trait and
//! check every kernel against the functions in [`cpu`].

#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod camera;
pub mod cpu;
pub mod error;
pub mod grid;
pub mod layout;
pub mod params;
pub mod render;
pub mod scene;
pub mod scene_file;
pub mod solver;
pub mod stats;
pub mod timing;
pub mod validate;

pub use camera::OrbitCamera;
pub use cpu::{CpuSolver, Exec, SIMD_ENV, Simd};
pub use grid::{ClothState, ClothTopology, Grab, Spring, SpringKind, SpringSlot, StepParams, build};
pub use params::{Integrator, ParamError, SimParams, StiffnessUnits};
pub use scene::{Aabb, ClothSpec, Pinning, Scene, Sphere};
pub use scene_file::{SceneFile, SceneFileError};
pub use solver::{RenderError, RenderMode, Renderer, Solver, SolverError, View};
pub use timing::{KernelId, KernelTimings, TimingRecorder, TimingRow};
