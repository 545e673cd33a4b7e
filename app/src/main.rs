//! `clothlab`: the interactive app (`clothlab` or `clothlab run`) and the command line.
//!
//! How it fits: the top of the workspace, over the `clothlab` library (which turns a
//! backend name into a solver, loads scenes with their overrides, renders, records,
//! validates and measures cells); `cli` is the command line as clap types, `commands` runs
//! `sim`, `render`, `validate` and the app; `bench` measures and writes the reports; `gui`
//! is the egui/winit app on any API. The guide to the commands is docs/cli.md.

#![forbid(unsafe_code)]

mod bench;
mod cli;
mod commands;
mod gui;
mod out;

use std::process::ExitCode;

/// Mesa's device-select layer (an implicit Vulkan layer) connects to the Wayland display
/// when an instance enables `VK_KHR_wayland_surface`, as wgpu's always does, and
/// libwayland prints `error: XDG_RUNTIME_DIR is invalid or not set` for every instance
/// where that variable is unset — which is exactly where no Wayland session runs (X11,
/// Xvfb, a terminal without a display). There, every command runs again with the layer
/// off (`NODEVICE_SELECT=1`, its documented switch; it only orders GPUs, and wgpu and
/// clothlab pick their own). Changing the environment of a running process is `unsafe`
/// (other threads may read it); replacing the process is not. On Unix the new image
/// replaces this one (`exec`: the same process id, so signals, Ctrl-C and the exit code
/// are the program's own); elsewhere a child runs and its exit code is returned.
fn rerun_without_device_select() -> Option<ExitCode> {
    let quiet = std::env::var_os("XDG_RUNTIME_DIR").is_some() || std::env::var_os("NODEVICE_SELECT").is_some();
    if quiet {
        return None;
    }
    let exe = std::env::current_exe().ok()?;
    let mut command = std::process::Command::new(exe);
    command.args(std::env::args_os().skip(1)).env("NODEVICE_SELECT", "1");
    #[cfg(unix)]
    {
        use std::os::unix::process::CommandExt;
        // Returns only if the exec failed; then this process goes on with the layer on.
        let e = command.exec();
        log::debug!("re-running without the device-select layer failed: {e}");
        None
    }
    #[cfg(not(unix))]
    {
        let status = command.status().ok()?;
        Some(match status.code() {
            Some(c) => ExitCode::from(c.clamp(0, 255) as u8),
            None => ExitCode::FAILURE,
        })
    }
}

fn main() -> ExitCode {
    if let Some(code) = rerun_without_device_select() {
        return code;
    }
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    match commands::run() {
        Ok(code) => code,
        // The reader went away (`| head`): end as a writer killed by SIGPIPE would, quietly.
        Err(e) if e.downcast_ref::<out::OutputError>().is_some_and(out::OutputError::is_closed_pipe) => {
            ExitCode::from(out::CLOSED_PIPE_STATUS)
        }
        Err(e) => {
            // One line: the error and its causes, no backtrace.
            let msg: Vec<String> = e.chain().map(|c| c.to_string()).collect();
            eprintln!("error: {}", msg.join(": "));
            ExitCode::FAILURE
        }
    }
}
