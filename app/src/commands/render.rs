//! `clothlab render`: simulate headless, then draw the scene into a PNG
//! (`clothlab::render`).

use std::process::ExitCode;

use anyhow::{Result, bail};
use clothlab::{Sim, SimOptions};

use crate::cli::RenderArgs;
use crate::out::outln;

/// Runs `render`.
pub fn render(args: RenderArgs) -> Result<ExitCode> {
    if args.frames > 100_000 {
        bail!("invalid --frames {}: must be in 0 ..= 100000", args.frames);
    }
    if !matches!(args.out.extension().and_then(|e| e.to_str()), Some("png" | "PNG")) {
        bail!("--out {}: the image is written as PNG, use a .png file name", args.out.display());
    }
    clothlab::files::check_writable(&args.out)?;
    let gpu = clothlab::GpuSetup { variant: args.variant.spec(args.backend)?, ..Default::default() };
    let api = args.api.or(args.backend.api()).unwrap_or(clothlab::Api::Wgpu);
    if let Some(own) = args.backend.api()
        && own != api
    {
        bail!(
            "--backend {} draws through its own API: a GPU solver's buffers are drawn without a copy, so pick --api {} (or a CPU backend)",
            args.backend.name(),
            own.name()
        );
    }
    let mut sim = Sim::open(SimOptions {
        backend: args.backend,
        physics: args.physics.physics(),
        n: args.n,
        gpu,
        envs: args.envs,
        grad: false,
    })?;
    if let Some(k) = args.world
        && k >= sim.envs()
    {
        bail!("invalid --world {k}: the batch has {} worlds (0 ..= {})", sim.envs(), sim.envs() - 1);
    }
    sim.step(u64::from(args.frames))?;
    let view = sim.view(args.mode.render_mode());
    let (pixels, adapter, drawn) = match args.world {
        Some(k) => {
            let (pixels, adapter) = sim.render_world(k, args.width, args.height, &view, Some(api))?;
            (pixels, adapter, format!(", world {k} of {}", sim.envs()))
        }
        None if sim.envs() > 1 => {
            let (pixels, adapter, worlds) = sim.render_worlds(0, args.width, args.height, &view, Some(api))?;
            let more = if worlds.len() < sim.envs() { " (--world K draws any one)" } else { "" };
            (
                pixels,
                adapter,
                format!(", worlds {} ..= {} of {} on a grid{more}", worlds.start, worlds.end - 1, sim.envs()),
            )
        }
        None => {
            let (pixels, adapter) = sim.render(args.width, args.height, &view, Some(api))?;
            (pixels, adapter, String::new())
        }
    };
    clothlab::files::write_png(&args.out, &pixels, args.width, args.height)?;
    outln!(
        "wrote {} ({}x{}, {} frames, {:?}{drawn}, adapter {adapter})",
        args.out.display(),
        args.width,
        args.height,
        args.frames,
        args.mode
    )?;
    Ok(ExitCode::SUCCESS)
}
