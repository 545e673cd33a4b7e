//! The step engine: integrators, recipes against the fast CPU solvers, self-collision.
//!
//! The crate's one integration-test binary: each module is a group of tests, linked once
//! with the whole stack rather than once per file (docs/testing.md, "Where a new test goes").

mod cpu_engine;
mod integrators;
mod self_collision;
