//! `clothlab`: the interactive app (`clothlab` or `clothlab run`) and the command line.

#![forbid(unsafe_code)]

mod bench;
mod cli;
mod commands;
mod gui;
mod overrides;
mod solvers;

use std::process::ExitCode;

/// The headless subcommands.
const HEADLESS: [&str; 4] = ["sim", "validate", "render", "bench"];

/// Mesa's device-select layer (an implicit Vulkan layer) connects to the Wayland display
/// when an instance enables `VK_KHR_wayland_surface`, as wgpu's always does, and
/// libwayland prints `error: XDG_RUNTIME_DIR is invalid or not set` for every instance
/// where that variable is unset. The headless commands need no display: where it is unset,
/// run them again with the layer off (`NODEVICE_SELECT=1`, its documented switch; it only
/// orders GPUs, and wgpu and clothlab pick their own). Changing the environment of a
/// running process is `unsafe` (other threads may read it), a child process is not.
fn rerun_without_device_select() -> Option<ExitCode> {
    let headless = std::env::args().nth(1).is_some_and(|c| HEADLESS.contains(&c.as_str()));
    let quiet = std::env::var_os("XDG_RUNTIME_DIR").is_some() || std::env::var_os("NODEVICE_SELECT").is_some();
    if !headless || quiet {
        return None;
    }
    let exe = std::env::current_exe().ok()?;
    let status =
        std::process::Command::new(exe).args(std::env::args_os().skip(1)).env("NODEVICE_SELECT", "1").status().ok()?;
    Some(match status.code() {
        Some(c) => ExitCode::from(c.clamp(0, 255) as u8),
        None => ExitCode::FAILURE,
    })
}

fn main() -> ExitCode {
    if let Some(code) = rerun_without_device_select() {
        return code;
    }
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    match commands::run() {
        Ok(code) => code,
        Err(e) => {
            // One line: the error and its causes, no backtrace.
            let msg: Vec<String> = e.chain().map(|c| c.to_string()).collect();
            eprintln!("error: {}", msg.join(": "));
            ExitCode::FAILURE
        }
    }
}
