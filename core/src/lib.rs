//! clothlab-core: the cloth model — cloths and meshes, scenes and their files, parameters,
//! motion and pins, the colliders' and the contacts' geometry — and the step's layout.
//!
//! Nothing here steps a cloth or touches a GPU. What every backend shares lives here: the
//! [`Solver`] trait, the order of a substep's stages ([`substep`]), the step's constants
//! ([`StepParams`]) and the GPU's binding table ([`layout`]). These are the model's and not
//! a backend's because both sides read them: the CPU twins (`clothlab-cpu`) compute from
//! the same `StepParams` the WGSL kernels read, and `clothlab-shaders` generates the WGSL
//! constants from [`layout`] and checks its structs against this crate's `#[repr(C)]`
//! types.
//!
//! How it fits the other crates: everything else depends on it. `clothlab-cpu` holds the
//! CPU backends (every kernel's twin, the serial and rayon solvers, the fused SIMD sweep,
//! the contact between triangles) and the comparison with them; `clothlab-engine`
//! registers each kernel with its CPU twin and runs recipes on any engine; the backends
//! (`clothlab-wgpu`, `clothlab-vulkan`, `clothlab-gl`) are `GpuSolver`s over that engine.
//! The state every backend carries is [`ClothState`]: positions and velocities (x, v),
//! both f32.

#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod broad;
pub mod camera;
pub mod cloth;
pub mod contact;
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

pub use camera::OrbitCamera;
pub use cloth::build;
pub use grid::{ClothState, ClothTopology, Grab, Spring, SpringKind, SpringSlot};
pub use motion::{Ease, Key, Motion, Repeat};
pub use params::{Integrator, ParamError, SelfCollision, SimParams, StiffnessUnits};
pub use pins::{MAX_PIN_GROUPS, PinGroup, PinPose, PinSlot};
pub use scene::{Aabb, ClothSpec, ColliderId, Pinning, Rod, RodKind, Scene, Sphere};
pub use scene_file::{SceneFile, SceneFileError};
pub use solver::{ContactStats, RenderError, RenderMode, Renderer, Solver, SolverError, StateField, View};
pub use step_params::StepParams;
pub use timing::{KernelTimings, TimingRecorder, TimingRow};
