//! `clothlab run` (and `clothlab` alone): the interactive app.

use std::process::ExitCode;

use anyhow::{Result, bail};

use crate::cli::RunArgs;

/// Opens the app.
pub fn run_app(args: RunArgs) -> Result<ExitCode> {
    // One world of a batch (the scene file's `envs`, the lists of `--set` and of its
    // `[params]`): its single run's parameters, named in the title.
    let world = args.world.unwrap_or(0);
    let opts = clothlab::SimOptions { physics: args.physics.physics(), n: args.n, ..Default::default() };
    let mut setup = opts.world(world).map_err(|e| anyhow::anyhow!("--world: {e:#}"))?.physics.setup(args.n, 64)?;
    if let Some(envs) = setup.envs.filter(|&e| e > 1) {
        let title = setup.title.take().map_or(String::new(), |t| format!("{t} "));
        setup.title = Some(format!("{title}(world {world} of {envs})"));
    }
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
