//! The clothlab binary: the CLI's good runs and bad input, the app under Xvfb, bench.
//!
//! The crate's one integration-test binary: each module is a group of tests, linked once
//! with the whole stack rather than once per file (docs/testing.md, "Where a new test goes").

mod bench;
mod cli;

use std::process::{Command, Output};

/// Runs the `clothlab` binary with `args`, a backtrace on any panic.
fn clothlab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_clothlab")).args(args).env("RUST_BACKTRACE", "1").output().expect("run clothlab")
}

/// Whether CI asked for the GPU tests to fail rather than skip without an adapter.
fn gpu_required() -> bool {
    std::env::var("CLOTHLAB_REQUIRE_GPU").is_ok_and(|v| v == "1")
}
