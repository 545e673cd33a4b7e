//! One module per subcommand (`bench` has its own folder), and the dispatch between them.

pub mod render;
pub mod run;
pub mod sim;
pub mod validate;

use std::process::ExitCode;

use anyhow::Result;
use clap::Parser;

use crate::cli::{Cli, Command, RunArgs};

/// Parses the command line and runs the command.
pub fn run() -> Result<ExitCode> {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            // clap's own message (usage and a hint); exit 0 only for --help / --version.
            let code = if e.use_stderr() { ExitCode::from(2) } else { ExitCode::SUCCESS };
            let _ = e.print();
            return Ok(code);
        }
    };
    if let Some(b) = cli.wgpu_backend {
        clothlab::backend::choose_wgpu_backends(b == crate::cli::WgpuBackend::Gl);
    }
    match cli.command.unwrap_or(Command::Run(RunArgs::default())) {
        Command::Run(args) => run::run_app(args),
        Command::Sim(args) => sim::sim(args),
        Command::Validate(args) => validate::validate(args),
        Command::Render(args) => render::render(args),
        Command::Bench(args) => crate::bench::bench(args),
    }
}
