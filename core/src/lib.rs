//! clothlab-core: the cloth model, its parameters and scene, and the CPU reference.
//!
//! Nothing here touches a GPU. The GPU backends implement the same [`Solver`] trait and
//! check every kernel against the functions in [`cpu`].
//!
//! How it fits the other crates: everything else depends on it. `clothlab-shaders`
//! generates the WGSL constants from [`layout`] and checks its structs against this
//! crate's `#[repr(C)]` types; `clothlab-engine` registers each kernel with its CPU twin
//! from [`cpu`] and runs recipes on any engine; the backends (`clothlab-wgpu`,
//! `clothlab-vulkan`, `clothlab-gl`) are `GpuSolver`s over that engine; the app and the tests compare
//! them all through [`validate`]. The state every engine carries is [`ClothState`]:
//! positions and velocities (x, v), both f32.

#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod broad;
pub mod camera;
pub mod cloth;
pub mod contact;
pub mod cpu;
pub mod crossings;
pub mod error;
pub mod grid;
pub mod input;
pub mod layout;
pub mod mesh;
pub mod motion;
pub mod params;
pub mod pins;
pub mod render;
pub mod scene;
pub mod scene_file;
pub mod sdf;
pub mod solver;
pub mod stats;
pub mod step_params;
pub mod substep;
pub mod tables;
pub mod timing;
pub mod tri_contact;
pub mod validate;

pub use camera::OrbitCamera;
pub use cloth::build;
pub use cpu::{CpuSolver, Exec, SIMD_ENV, Simd};
pub use grid::{ClothState, ClothTopology, Grab, Spring, SpringKind, SpringSlot};
pub use motion::{Ease, Key, Motion, Repeat};
pub use params::{Integrator, ParamError, SelfCollision, SimParams, StiffnessUnits};
pub use pins::{MAX_PIN_GROUPS, PinGroup, PinPose, PinSlot};
pub use scene::{Aabb, Capsule, ClothSpec, ColliderId, Cylinder, Pinning, Scene, Sphere};
pub use scene_file::{SceneFile, SceneFileError};
pub use solver::{ContactStats, RenderError, RenderMode, Renderer, Solver, SolverError, StateField, View};
pub use step_params::StepParams;
pub use timing::{KernelTimings, TimingRecorder, TimingRow};
