//! `clothlab run` (and `clothlab` alone): the interactive app.

use std::process::ExitCode;

use anyhow::{Result, bail};

use crate::cli::RunArgs;

/// Opens the app.
pub fn run_app(args: RunArgs) -> Result<ExitCode> {
    let setup = args.physics.setup(args.n, 64)?;
    let n = setup.scene.cloth.n;
    if !(10..=1024).contains(&n) {
        bail!("invalid --n {n}: the app takes 10 ..= 1024 particles per side");
    }
    let backend = args.backend.unwrap_or(args.api.optimized());
    crate::gui::run(crate::gui::RunOptions {
        api: args.api,
        backend,
        frames: args.frames,
        screenshot: args.screenshot,
        size: (args.width, args.height),
        drag_test: args.drag_test,
        switch_api: args.switch_api,
        drop_file: args.drop_file,
        setup,
    })
}
