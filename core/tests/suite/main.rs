//! The cloth model: meshes and their files (the solvers' tests are clothlab-cpu's).
//!
//! The crate's one integration-test binary: each module is a group of tests, linked once
//! rather than once per file (docs/testing.md, "Where a new test goes").

mod mesh_files;
