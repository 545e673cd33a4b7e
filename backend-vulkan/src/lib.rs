//! clothlab-vulkan: the naive and optimized solvers and the renderer on raw Vulkan (ash).
//!
//! Empty until the Vulkan-solver issue. This will be the only crate with `unsafe`, kept in
//! one small `raw` module behind safe RAII types.
