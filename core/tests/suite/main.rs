//! The CPU reference: physics, meshes, scene files, the fused sweep, VBD.
//!
//! The crate's one integration-test binary: each module is a group of tests, linked once
//! with the whole stack rather than once per file (docs/testing.md, "Where a new test goes").

mod cloths;
mod contact;
mod fused;
mod mesh_cloth;
mod mesh_files;
mod physics;
mod vbd;
