//! clothlab as a library: open a scene on any backend by name — the CPU (serial or rayon),
//! wgpu, raw Vulkan or raw OpenGL, each GPU API naive or optimized — step it, read and
//! write its state, grab a particle, draw it, record it, check its kernels against their
//! CPU twins and measure it. The command line, the app and the Python package are built on
//! this crate.
//!
//! ```no_run
//! use clothlab::{Backend, Physics, SceneSource, Sim, SimOptions};
//!
//! let mut sim = Sim::open(SimOptions {
//!     backend: Backend::parse("vulkan")?,
//!     physics: Physics { scene: SceneSource::File("scenes/heap.toml".into()), ..Default::default() },
//!     ..Default::default()
//! })?;
//! sim.set(&["damping=0.001".to_string()])?;
//! sim.step(60)?;
//! println!("{} on {}: {} particles at t = {} s", sim.name(), sim.adapter(), sim.num_particles(), sim.time());
//! # Ok::<(), anyhow::Error>(())
//! ```
//!
//! * [`Sim`] — a scene on a backend ([`SimOptions`]: the backend, the scene and its
//!   overrides ([`Physics`]), the grid size, a GPU variant ([`GpuSetup`]));
//! * [`backend`] — the backends and APIs by name, and [`make`], the one factory of
//!   solvers ([`AnySolver`]);
//! * [`setup`] — scenes from files, text or the default, with overrides;
//! * [`validate()`] — every GPU kernel against its twin and rollouts against the CPU;
//! * [`bench`](mod@bench) — per-kernel and per-frame times of backends at sizes, as data;
//! * [`render`] — offscreen pictures; [`record`] — runs as binary glTF; [`files`] —
//!   atomic writes.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod backend;
pub mod bench;
pub mod files;
pub mod record;
pub mod render;
pub mod setup;
mod sim;
pub mod validate;

pub use anyhow::{Error, Result};
pub use backend::{AnySolver, Api, Backend, GpuSetup, Shared, make, variant_spec};
pub use clothlab_core::{ClothState, Integrator, KernelTimings, RenderMode, Scene, SimParams, TimingRow, View};
pub use clothlab_cpu::grad::{Gradients, PARAMS as GRAD_PARAMS};
pub use clothlab_engine::{SolverOptions, StatsMode, VariantSpec};
pub use setup::{Physics, SceneSource, Setup, apply_overrides};
pub use sim::{ClothRange, DEFAULT_N, MAX_STEPS, MOSAIC_WORLDS, Sim, SimOptions, available};
pub use validate::{ValidateOptions, Validation, validate};

/// The crates underneath, for what the facade does not wrap: the model (its types are the
/// library's: `Scene`, `SimParams`, …), the CPU backends and the step as data.
pub use {clothlab_core as core, clothlab_cpu as cpu, clothlab_engine as engine};
