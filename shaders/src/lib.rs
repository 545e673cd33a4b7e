//! clothlab-shaders: the WGSL kernels of the step and their build-time checks.
//!
//! Empty until the wgpu-solver issue adds one WGSL file per kernel of DESIGN.md's step
//! table, a `build.rs` that validates them with naga and checks the shared struct layouts
//! against `clothlab_core`'s `#[repr(C)]` types, and the SPIR-V the Vulkan backend loads.
#![forbid(unsafe_code)]
