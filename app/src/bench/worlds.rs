//! `clothlab bench --envs N,..`: what a batch of worlds costs per world.
//!
//! At each size and each count of worlds, the scene runs as one batch (`SimOptions::envs`)
//! and as the same worlds opened as separate simulations and stepped one after another
//! (at most [`SEPARATE_MOST`] of them: the time per world-substep is what is compared). A
//! backend that cannot run a batch gets a note with its one-line refusal. Opening is not
//! timed; each cell is stepped [`WARMUP_FRAMES`] frames, then timed over its frames, the
//! rounds interleaved; the report gives the median of the rounds and their spread.

use std::fmt::Write as _;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Result;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::plot::{FONT, Figure, both, err};
use super::{Request, WARMUP_FRAMES, all_backends, cpu_label, make_out_dir};
use crate::cli::BenchArgs;
use crate::out::outln;
use clothlab::{Backend, Sim, SimOptions};

/// The backends measured unless `--backends` says otherwise: the CPU's two and each GPU
/// API's optimized recipe.
pub const DEFAULT_BACKENDS: [Backend; 5] = [Backend::Cpu, Backend::CpuPar, Backend::Wgpu, Backend::Vulkan, Backend::Gl];

/// The most worlds run as separate simulations for a cell.
pub const SEPARATE_MOST: u32 = 64;

/// One cell: a count of worlds of a size on a backend.
#[derive(Debug, Clone)]
pub struct Row {
    /// Particles per side.
    pub n: u32,
    /// Backend name.
    pub backend: String,
    /// Worlds.
    pub envs: u32,
    /// The batch: µs per world-substep (median over rounds) and the rounds' spread.
    pub batched_us: f64,
    /// (largest − smallest) / median of the batch's rounds.
    pub spread: f64,
    /// The same worlds as separate simulations (at most [`SEPARATE_MOST`]): µs per
    /// world-substep, median over rounds.
    pub separate_us: f64,
}

/// The options of a cell's simulations.
fn options(args: &BenchArgs, backend: Backend, n: u32, envs: u32) -> SimOptions {
    SimOptions { backend, physics: args.physics.physics(), n: Some(n), envs: Some(envs), ..Default::default() }
}

/// Steps every simulation of `sims` `frames` frames, one after another each frame, after
/// the warm-up; µs per world-substep.
fn time(sims: &mut [Sim], frames: u32) -> Result<f64> {
    for s in sims.iter_mut() {
        s.step(WARMUP_FRAMES as u64)?;
    }
    let t0 = Instant::now();
    for _ in 0..frames {
        for s in sims.iter_mut() {
            s.step(1)?;
        }
    }
    let elapsed = t0.elapsed().as_secs_f64() * 1e6;
    let world_substeps: f64 = sims.iter().map(|s| (s.envs() as u64 * s.params().substeps as u64) as f64).sum();
    Ok(elapsed / (world_substeps * frames as f64))
}

/// The median of `v` and the spread (largest − smallest) / median.
fn median_spread(mut v: Vec<f64>) -> (f64, f64) {
    v.sort_by(f64::total_cmp);
    let m = v[v.len() / 2];
    (m, (v[v.len() - 1] - v[0]) / m)
}

/// Measures every cell `repeat` times, interleaved; the rows and the notes (refusals).
pub fn measure(
    args: &BenchArgs,
    backends: &[Backend],
    sizes: &[u32],
    envs: &[u32],
    frames: u32,
) -> Result<(Vec<Row>, Vec<String>)> {
    let mut cells = Vec::new();
    let mut notes = Vec::new();
    for &n in sizes {
        for &b in backends {
            // Whether the backend takes a batch: a batch of two opened, or its refusal.
            match Sim::open(options(args, b, n, 2)) {
                Ok(_) => cells.extend(envs.iter().map(|&e| (n, b, e))),
                Err(e) => notes.push(format!("{} at n = {n}: {e:#}", b.name())),
            }
        }
    }
    let mut batched = vec![Vec::new(); cells.len()];
    let mut separate = vec![Vec::new(); cells.len()];
    for round in 0..args.repeat {
        for (k, &(n, b, e)) in cells.iter().enumerate() {
            let mut batch = [Sim::open(options(args, b, n, e))?];
            let us = time(&mut batch, frames)?;
            drop(batch);
            let mut apart: Vec<Sim> =
                (0..e.min(SEPARATE_MOST)).map(|_| Sim::open(options(args, b, n, 1))).collect::<Result<_>>()?;
            let apart_us = time(&mut apart, frames)?;
            eprintln!(
                "round {round}: {:8} n = {n:4} {e:5} worlds: batch {us:9.2} us, separate {apart_us:9.2} us per world-substep",
                b.name()
            );
            batched[k].push(us);
            separate[k].push(apart_us);
        }
    }
    let rows = cells
        .into_iter()
        .zip(batched.into_iter().zip(separate))
        .map(|((n, b, e), (bt, sp))| {
            let (batched_us, spread) = median_spread(bt);
            Row { n, backend: b.name().into(), envs: e, batched_us, spread, separate_us: median_spread(sp).0 }
        })
        .collect();
    Ok((rows, notes))
}

/// The report: a table per size, the notes.
pub fn report(rows: &[Row], notes: &[String], machine: &str, repeat: u32, frames: u32) -> String {
    let mut s = String::from("# Worlds: a batch against separate simulations\n\n");
    let _ = writeln!(
        s,
        "{machine}; {repeat} interleaved round(s) per cell, each {frames} frames after {WARMUP_FRAMES} warm-up frames. \
         µs per world-substep (wall time); `separate`: the same worlds (at most {SEPARATE_MOST}) opened as single \
         simulations and stepped one after another; `gain`: separate over batch.\n"
    );
    let mut sizes: Vec<u32> = rows.iter().map(|r| r.n).collect();
    sizes.dedup();
    for n in sizes {
        let _ = writeln!(s, "## n = {n} ({} particles a world)\n", n * n);
        let _ = writeln!(
            s,
            "| backend | worlds | batch, µs | world-substeps/s | spread | separate, µs | gain |\n|---|---:|---:|---:|---:|---:|---:|"
        );
        for r in rows.iter().filter(|r| r.n == n) {
            let _ = writeln!(
                s,
                "| {} | {} | {:.2} | {:.0} | {:.0} % | {:.2} | {:.2} |",
                r.backend,
                r.envs,
                r.batched_us,
                1e6 / r.batched_us,
                100.0 * r.spread,
                r.separate_us,
                r.separate_us / r.batched_us
            );
        }
        s.push('\n');
    }
    if !notes.is_empty() {
        s.push_str("## Not measured\n\n");
        for note in notes {
            let _ = writeln!(s, "- {note}");
        }
        s.push('\n');
    }
    s.push_str("![µs per world-substep against worlds](worlds.png)\n");
    s
}

/// The rows as CSV.
pub fn csv(rows: &[Row]) -> String {
    let mut s = String::from("n,backend,envs,batched_us,spread,separate_us\n");
    for r in rows {
        let _ =
            writeln!(s, "{},{},{},{:.4},{:.4},{:.4}", r.n, r.backend, r.envs, r.batched_us, r.spread, r.separate_us);
    }
    s
}

/// Draws worlds.{svg,png} of `out`/worlds.csv again (`bench --envs .. --replot`); the
/// machine's label is read from the report beside it (its line after the title).
pub fn replot(out: &std::path::Path) -> Result<Vec<std::path::PathBuf>> {
    use anyhow::Context as _;
    let path = out.join("worlds.csv");
    let text = std::fs::read_to_string(&path).with_context(|| format!("cannot read {}", path.display()))?;
    let rows = text
        .lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let num = |k: usize| -> Result<f64> {
                f.get(k)
                    .and_then(|v| v.parse().ok())
                    .with_context(|| format!("{}: `{l}` is not a row of a worlds run", path.display()))
            };
            Ok(Row {
                n: num(0)? as u32,
                backend: f[1].to_owned(),
                envs: num(2)? as u32,
                batched_us: num(3)?,
                spread: num(4)?,
                separate_us: num(5)?,
            })
        })
        .collect::<Result<Vec<Row>>>()?;
    let md = std::fs::read_to_string(out.join("worlds.md")).unwrap_or_default();
    let machine = md.lines().nth(2).and_then(|l| l.split(';').next()).unwrap_or("unknown machine").to_owned();
    let (svg, png) = both(&Lines { rows: &rows, machine: &machine })?;
    let files = [out.join("worlds.svg"), out.join("worlds.png")];
    clothlab::files::write_bytes(&files[0], svg.as_bytes())?;
    clothlab::files::write_bytes(&files[1], &png)?;
    Ok(files.to_vec())
}

/// Lines: µs per world-substep against worlds (log axes), a line per backend and size,
/// the batch solid and the separate runs dashed.
struct Lines<'a> {
    rows: &'a [Row],
    machine: &'a str,
}

impl Figure for Lines<'_> {
    fn size(&self) -> (u32, u32) {
        (1000, 600)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(err)?;
        let most = self.rows.iter().map(|r| r.envs).max().unwrap_or(1).max(2) as f64;
        let values = self.rows.iter().flat_map(|r| [r.batched_us, r.separate_us]);
        let (lo, hi) = values.fold((f64::INFINITY, 0f64), |(lo, hi), v| (lo.min(v), hi.max(v)));
        let (lo, hi) = if lo.is_finite() { (lo * 0.7, hi * 1.4) } else { (0.1, 10.0) };
        let mut chart = ChartBuilder::on(root)
            .caption(format!("A batch of worlds against separate simulations — {}", self.machine), (FONT, 20))
            .margin(12)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .build_cartesian_2d((1f64..most * 1.3).log_scale(), (lo..hi).log_scale())
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("worlds")
            .y_desc("µs per world-substep")
            .label_style((FONT, 13))
            .draw()
            .map_err(err)?;
        let mut lines: Vec<(u32, &str)> = self.rows.iter().map(|r| (r.n, r.backend.as_str())).collect();
        lines.dedup();
        // A colour a backend (the five default ones apart), a wider line a larger size.
        let palette = [
            RGBColor(40, 90, 170),
            RGBColor(220, 120, 40),
            RGBColor(90, 160, 80),
            RGBColor(160, 60, 160),
            RGBColor(200, 50, 50),
            RGBColor(60, 170, 180),
        ];
        let mut backends: Vec<&str> = Vec::new();
        let mut sizes: Vec<u32> = Vec::new();
        for &(n, b) in &lines {
            if !backends.contains(&b) {
                backends.push(b);
            }
            if !sizes.contains(&n) {
                sizes.push(n);
            }
        }
        for (n, b) in &lines {
            let colour = palette[backends.iter().position(|x| x == b).unwrap_or(0) % palette.len()];
            let wide = sizes.iter().position(|x| x == n).unwrap_or(0) as u32;
            let of: Vec<&Row> = self.rows.iter().filter(|r| r.n == *n && r.backend == *b).collect();
            chart
                .draw_series(LineSeries::new(
                    of.iter().map(|r| (r.envs as f64, r.batched_us)),
                    colour.stroke_width(2 + wide),
                ))
                .map_err(err)?
                .label(format!("{b}, n = {n}: batch"))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2 + wide)));
            chart
                .draw_series(DashedLineSeries::new(
                    of.iter().map(|r| (r.envs as f64, r.separate_us)),
                    6,
                    4,
                    colour.stroke_width(1 + wide),
                ))
                .map_err(err)?
                .label(format!("{b}, n = {n}: separate"))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(1 + wide)));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .label_font((FONT, 14))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(err)?;
        Ok(())
    }
}

/// `bench --envs N,..`: [`measure`], the files and the report, with the mode's defaults:
/// sizes 16 and 32 where left at the default, the backends, if left at all of them, the
/// CPU ones. Refused in one line: a count of worlds out of range.
pub fn run(args: &BenchArgs, request: &Request) -> Result<ExitCode> {
    let mut envs = args.envs.clone();
    if let Some(&e) = envs.iter().find(|&&e| !(1..=clothlab::core::scene_file::MAX_ENVS).contains(&e)) {
        anyhow::bail!("invalid --envs {e}: a count of worlds is in 1 ..= {}", clothlab::core::scene_file::MAX_ENVS);
    }
    envs.sort_unstable();
    envs.dedup();
    let defaults = BenchArgs::default_sizes();
    let sizes: Vec<u32> = if request.sizes == defaults { vec![16, 32] } else { request.sizes.clone() };
    let backends: Vec<Backend> =
        if all_backends(&request.backends) { DEFAULT_BACKENDS.to_vec() } else { request.backends.clone() };
    let frames = args.iters.div_ceil(request.params.substeps).max(1);
    make_out_dir(&args.out)?;
    let (rows, notes) = measure(args, &backends, &sizes, &envs, frames)?;
    let machine = args.machine.clone().unwrap_or_else(cpu_label);
    let text = report(&rows, &notes, &machine, args.repeat, frames);
    clothlab::files::write_bytes(&args.out.join("worlds.csv"), csv(&rows).as_bytes())?;
    clothlab::files::write_bytes(&args.out.join("worlds.md"), text.as_bytes())?;
    let (svg, png) = both(&Lines { rows: &rows, machine: &machine })?;
    clothlab::files::write_bytes(&args.out.join("worlds.svg"), svg.as_bytes())?;
    clothlab::files::write_bytes(&args.out.join("worlds.png"), &png)?;
    outln!("{text}")?;
    outln!("wrote {}/worlds.{{md,csv,svg,png}}", args.out.display())?;
    Ok(ExitCode::SUCCESS)
}
