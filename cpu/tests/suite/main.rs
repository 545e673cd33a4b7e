//! The CPU backends: physics, several cloths, the contact between triangles, the fused
//! sweep, meshes on the solvers, VBD.
//!
//! The crate's one integration-test binary: each module is a group of tests, linked once
//! rather than once per file (docs/testing.md, "Where a new test goes").

mod cloths;
mod contact;
mod fused;
mod grad;
mod mesh_cloth;
mod physics;
mod vbd;
