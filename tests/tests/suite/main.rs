//! Cross-backend tests: each GPU API against the CPU twins, physics on every backend, pictures.
//!
//! The crate's one integration-test binary: each module is a group of tests, linked once
//! with the whole stack rather than once per file (docs/testing.md, "Where a new test goes").

mod api_vs_cpu;
mod bit_identity;
mod bodies;
mod capsules;
mod cloth_friction;
mod cones;
mod custom_kernel;
mod cylinders;
mod docs_names;
mod dt_change;
mod free_fall;
mod friction;
mod gl_render;
mod grad;
mod integrators;
mod mesh_gpu;
mod module_graph;
mod momentum;
mod motion;
mod pins;
mod render;
mod scenes;
mod self_collision;
mod specialize;
mod subgroup_shuffle;
mod tile;
mod tri_contact;
mod two_cloths;
mod vulkan_render;
mod vulkan_window;
mod wgpu_on_gl;
mod worlds;
