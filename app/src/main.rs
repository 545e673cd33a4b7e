//! `clothlab`: the interactive app (`clothlab` or `clothlab run`) and the command line.

#![forbid(unsafe_code)]

mod bench;
mod cli;
mod gui;

use std::process::ExitCode;

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    match cli::run() {
        Ok(code) => code,
        Err(e) => {
            // One line: the error and its causes, no backtrace.
            let msg: Vec<String> = e.chain().map(|c| c.to_string()).collect();
            eprintln!("error: {}", msg.join(": "));
            ExitCode::FAILURE
        }
    }
}
