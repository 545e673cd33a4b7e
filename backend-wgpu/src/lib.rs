//! clothlab-wgpu: the naive and optimized solvers and the renderer on wgpu.
//!
//! Empty until the wgpu-solver issue; nothing here pretends to simulate yet.
#![forbid(unsafe_code)]
