//! clothlab-tests: tests that span backends (GPU vs CPU, golden images, soak runs).
//!
//! The CPU reference's own tests live in `core/tests`; the CLI's in `app/tests`. This crate
//! receives the GPU-vs-CPU comparisons when the GPU backends land.
#![forbid(unsafe_code)]
