//! `clothlab bench`: the thesis's chapter 7 for every backend — per-kernel times, time per
//! frame and frames per second against grid size — plus the API-overhead micro-benchmarks
//! (wgpu vs raw Vulkan), written as CSV, JSON, a Markdown report and plots.
//!
//! Every backend × size cell runs the same workload: the default scene and parameters,
//! `warmup` frames, then `frames` frames with per-kernel timing on (the kernel table),
//! then `frames` frames with it off, each followed by an offscreen render of the scene (the
//! frame table). The final positions of 25 particles are compared with the first backend
//! that ran at that size, so a backend cannot be fast by doing less.
//!
//! [`bench()`] checks what every mode reads ([`Request`]) and hands it to the mode's module:
//! `cells` (the backends, or `--ladder`'s rungs, at every size, and the API overheads),
//! `integrators` (`--integrators`), `mesh_grid` (`--mesh-vs-grid`), `worlds` (`--envs`);
//! `--replot` redraws a finished run.

mod cells;
mod integrators;
mod journal;
mod ladder;
mod mesh_grid;
mod output;
mod plot;
mod results;
mod worlds;

use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clothlab::core::{Scene, SimParams};

use crate::cli::BenchArgs;
use crate::out::outln;
use clothlab::backend::Backend;

/// Whether `backends` is every backend (`--backends` left at its default).
fn all_backends(backends: &[Backend]) -> bool {
    backends.len() == Backend::ALL.len()
}

/// Makes the output folder: only once every argument has been checked, so that a refused
/// run leaves nothing behind.
fn make_out_dir(dir: &std::path::Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))
}

pub use clothlab::bench::{WARMUP_FRAMES, cpu_label};

/// What every measuring mode reads, checked before the output folder is made: the sizes
/// (sorted, each once), the backends (each once), the scene of `--scene` or the default
/// one with its parameters (checked at every size where the cloth is a grid).
struct Request {
    sizes: Vec<u32>,
    backends: Vec<Backend>,
    base: Scene,
    params: SimParams,
    scene_label: String,
}

impl Request {
    fn checked(args: &BenchArgs) -> Result<Self> {
        let mut sizes = args.sizes.clone();
        if sizes.is_empty() {
            bail!("--sizes is empty: give at least one grid size");
        }
        if let Some(&n) = sizes.iter().find(|&&n| !(2..=4096).contains(&n)) {
            bail!("invalid size {n} in --sizes: grid sizes must be in 2 ..= 4096");
        }
        sizes.sort_unstable();
        sizes.dedup();
        if args.iters == 0 || args.iters > 1_000_000 {
            bail!("invalid --iters {}: must be in 1 ..= 1000000", args.iters);
        }
        if !(1..=20).contains(&args.repeat) {
            bail!("invalid --repeat {}: must be in 1 ..= 20", args.repeat);
        }
        if !(args.cell_budget > 0.0 && args.cell_budget.is_finite()) {
            bail!("invalid --cell-budget {}: must be a positive number of seconds", args.cell_budget);
        }
        let mut backends = Vec::new();
        for b in &args.backends {
            if !backends.contains(b) {
                backends.push(*b);
            }
        }
        if backends.is_empty() {
            bail!("--backends is empty: name at least one backend");
        }
        // The scene of --scene (or the default one), at every size of --sizes: everything is
        // checked before the output folder is made.
        let loaded = args.physics.setup(None, sizes[0])?;
        let scene_label = match (&loaded.title, &args.physics.scene) {
            (Some(t), Some(f)) => format!("{t} ({})", f.display()),
            (None, Some(f)) => f.display().to_string(),
            _ => "default scene".to_owned(),
        };
        let (base, params) = (loaded.scene, loaded.params);
        let sized = |n: u32| {
            let mut s = base.clone();
            s.cloth.n = n;
            s
        };
        if base.cloth.is_mesh() {
            clothlab::core::cloth::check_params(&base, &params)?;
        } else if !args.integrators {
            for &n in &sizes {
                clothlab::core::cloth::check_params(&sized(n), &params)
                    .with_context(|| format!("the scene's parameters at size {n} of --sizes"))?;
            }
        }
        Ok(Self { sizes, backends, base, params, scene_label })
    }
}

/// Runs `bench`: `--resume` and `--replot` here, then the mode's module.
pub fn bench(mut args: BenchArgs) -> Result<ExitCode> {
    if let Some(dir) = &args.resume {
        if args.out != std::path::Path::new("bench-out") && &args.out != dir {
            bail!("--resume {} writes there: leave out --out {}", dir.display(), args.out.display());
        }
        // Checked before anything is created there.
        if !dir.join(journal::FILE).is_file() {
            bail!("--resume {}: no {} there (not a folder a bench run wrote)", dir.display(), journal::FILE);
        }
        args.out = dir.clone();
    }
    if args.replot && !args.envs.is_empty() {
        for f in worlds::replot(&args.out)? {
            outln!("wrote {}", f.display())?;
        }
        return Ok(ExitCode::SUCCESS);
    }
    if args.replot && args.integrators {
        for f in integrators::replot(&args.out)? {
            outln!("wrote {}", f.display())?;
        }
        return Ok(ExitCode::SUCCESS);
    }
    if args.replot {
        let path = args.out.join("results.json");
        let text = std::fs::read_to_string(&path).with_context(|| format!("cannot read {}", path.display()))?;
        let mut results: results::Results = serde_json::from_str(&text)
            .with_context(|| format!("{} is not a clothlab bench result", path.display()))?;
        if args.peak_gbps.is_some() {
            results.peak_gbps = args.peak_gbps;
        }
        for f in output::write_report(&results, &args.out)? {
            outln!("wrote {}", f.display())?;
        }
        return Ok(ExitCode::SUCCESS);
    }
    let request = Request::checked(&args)?;
    if args.integrators {
        return integrators::run(&args, &request);
    }
    if args.mesh_vs_grid {
        return mesh_grid::run(&args, &request);
    }
    if !args.envs.is_empty() {
        return worlds::run(&args, &request);
    }
    cells::run(&args, request)
}
