//! `bench`'s default mode: every backend (or with `--ladder` every rung of each GPU API's
//! ladder and the thesis preset) at every size, `--repeat` rounds interleaved, resumable
//! from its journal; then the API-overhead micro-benchmarks; the results written as
//! CSV, JSON, a report and plots.

use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clothlab::core::timing::{OverheadPlan, OverheadRow};
use clothlab::core::{Scene, SimParams};
use clothlab::engine::variant::{Variant, ladder as ladder_rungs};
use indicatif::{ProgressBar, ProgressStyle};

use clothlab::bench::{Devices, is_gl, is_vulkan, is_wgpu, measure};

use super::results::{self, Cell, LadderCell};
use super::{Request, WARMUP_FRAMES, cpu_label, journal, make_out_dir, output};
use crate::cli::BenchArgs;
use crate::out::outln;
use clothlab::backend::{Api, Backend, GpuSetup, Shared, make};

/// The cells of `request` as `args` asks, and the overhead benchmarks.
pub fn run(args: &BenchArgs, request: Request) -> Result<ExitCode> {
    let Request { sizes, mut backends, base, params, scene_label } = request;
    let sized = |n: u32| {
        let mut s = base.clone();
        s.cloth.n = n;
        s
    };
    let frames = args.iters.div_ceil(params.substeps);
    let overhead_plan = OverheadPlan {
        samples: args.iters.clamp(5, 1000) as usize,
        warmup: (args.iters / 10).clamp(2, 50) as usize,
        ..Default::default()
    };
    // Every backend draws its frames; CPU backends draw through wgpu (or Vulkan without it).
    let need_wgpu = backends.iter().any(|&b| is_wgpu(b) || !is_vulkan(b)) || !args.no_overhead;
    let need_vulkan = backends.iter().any(|&b| is_vulkan(b)) || !args.no_overhead;
    let need_gl = backends.iter().any(|&b| is_gl(b)) || !args.no_overhead;
    let devices = Devices::open(need_wgpu, need_vulkan, need_gl);
    let mut notes = Vec::new();
    for (api, err, present) in [
        ("wgpu", &devices.wgpu_error, backends.iter().any(|&b| is_wgpu(b))),
        ("Vulkan", &devices.vulkan_error, backends.iter().any(|&b| is_vulkan(b))),
        ("OpenGL", &devices.gl_error, backends.iter().any(|&b| is_gl(b))),
    ] {
        if let Some(e) = err {
            let what = if present { "its backends and overhead benchmarks are skipped" } else { "skipped" };
            eprintln!("note: no {api} adapter ({e}); {what}");
            notes.push(format!("no {api} adapter: {e}"));
        }
    }
    backends.retain(|&b| {
        !(is_wgpu(b) && devices.wgpu.is_none()
            || is_vulkan(b) && devices.vulkan.is_none()
            || is_gl(b) && devices.gl.is_none())
    });
    if backends.is_empty() {
        bail!("none of the requested backends can run here (no GPU adapter); try --backends cpu,cpu-par");
    }

    // What runs at every size: the backends (a GPU one with the variant asked for), or with
    // --ladder the rungs of each GPU API's ladder and the thesis preset.
    let mut jobs: Vec<Job> = Vec::new();
    if args.ladder {
        for api in [Api::Wgpu, Api::Vulkan, Api::Gl] {
            if !backends.iter().any(|b| b.api() == Some(api)) {
                continue;
            }
            let backend = api.naive();
            let probe = make(backend, Scene::with_n(4), params.clone(), &GpuSetup::default(), &Shared::None)
                .with_context(|| format!("probing {} for the ladder", backend.name()))?;
            let (caps, api_name) = probe.caps().context("a GPU backend")?;
            drop(probe);
            let rungs = ladder_rungs(&caps, api_name);
            let last = rungs.len();
            for (index, rung) in rungs.into_iter().enumerate() {
                jobs.push(Job { backend, variant: Some(rung.variant), rung: Some((index, rung.name(), rung.skipped)) });
            }
            let thesis = Variant::THESIS.fit(&caps);
            jobs.push(Job { backend, variant: Some(thesis), rung: Some((last, "thesis (preset)".into(), None)) });
        }
        if jobs.is_empty() {
            bail!("--ladder climbs the GPU backends' variants: name at least one GPU backend in --backends");
        }
    } else {
        let asked = args.variant.variant.is_some() || !args.variant.set_variant.is_empty();
        if asked && backends.iter().all(|b| b.api().is_none()) {
            bail!("--variant and --set-variant apply to the GPU backends: name one in --backends");
        }
        for &backend in &backends {
            // The CPU backends run their own step whatever the variant; a GPU backend's
            // is resolved on its adapter now (a switch it lacks is refused before any cell).
            let variant = match backend.api().and(args.variant.spec(backend).transpose()) {
                Some(spec) => {
                    let setup = GpuSetup { variant: Some(spec?), ..GpuSetup::default() };
                    make(backend, Scene::with_n(4), params.clone(), &setup, &Shared::None)?.variant()
                }
                None => None,
            };
            jobs.push(Job { backend, variant, rung: None });
        }
    }

    let overhead_apis = usize::from(!args.no_overhead && devices.wgpu.is_some())
        + usize::from(!args.no_overhead && devices.wgpu_gl.is_some())
        + usize::from(!args.no_overhead && devices.vulkan.is_some())
        + usize::from(!args.no_overhead && devices.gl.is_some());
    let bar = ProgressBar::new((sizes.len() * jobs.len() * args.repeat as usize + overhead_apis) as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:32} {pos}/{len} [{elapsed_precise}] {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let say = |bar: &ProgressBar, line: String| bar.suspend(|| eprintln!("{line}"));

    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let machine = args.machine.clone().unwrap_or_else(cpu_label);
    let plan = journal::Plan {
        command: command.clone(),
        build: journal::Plan::build_id(),
        machine: machine.clone(),
        wgpu_adapter: devices.wgpu.as_ref().map(|c| c.describe()),
        vulkan_adapter: devices.vulkan.as_ref().map(|d| d.name().to_owned()),
        gl_adapter: devices.gl.clone(),
        jobs: jobs.iter().map(Job::label).collect(),
        sizes: sizes.clone(),
        frames,
        repeat: args.repeat,
        resolution: args.resolution,
        cell_budget: args.cell_budget,
        overhead: !args.no_overhead,
        setup: serde_json::json!({ "params": params, "scene": base }),
    };
    let mut journal = match &args.resume {
        Some(dir) => journal::Journal::resume(dir, &plan)?,
        None => {
            make_out_dir(&args.out)?;
            journal::Journal::create(&args.out, &plan)?
        }
    };
    if args.resume.is_some() {
        eprintln!("resuming: {} cells measured before", journal.resumed_cells());
    }
    journal::catch_signals();
    let total_cells = sizes.len() * jobs.len() * args.repeat as usize;
    let mut done_cells = 0usize;
    let mut interrupted = false;
    let mut resumed_seconds = 0.0;

    let started = Instant::now();
    let mut cells: Vec<Cell> = Vec::new();
    let mut skipped: Vec<String> = Vec::new();
    let mut ladder: Vec<LadderCell> = Vec::new();
    'sizes: for &n in &sizes {
        // --repeat rounds, interleaved (A B C … A B C …), so that the machine's slow and
        // fast phases fall on every job alike; merged below.
        let mut runs: Vec<Vec<Cell>> = vec![Vec::new(); jobs.len()];
        let mut skip = vec![false; jobs.len()];
        'rounds: for round in 0..args.repeat {
            for (j, job) in jobs.iter().enumerate() {
                if journal::stopping() {
                    interrupted = true;
                    break 'rounds;
                }
                done_cells += 1;
                let label = job.label();
                bar.set_message(format!("{label} n={n} round {}/{}", round + 1, args.repeat));
                if skip[j] || matches!(&job.rung, Some((_, _, Some(_)))) {
                    bar.inc(1);
                    continue;
                }
                // A stopped run's cells, when resuming: taken as measured.
                if let Some(line) = journal.skipped(n, &label) {
                    skipped.push(line);
                    skip[j] = true;
                    bar.inc(1);
                    continue;
                }
                if let Some(cell) = journal.cell(n, &label, round) {
                    resumed_seconds += cell.seconds;
                    runs[j].push(cell);
                    bar.inc(1);
                    continue;
                }
                // Predict the cell's time from this job's previous size (time ∝ particles).
                let predicted = cells
                    .iter()
                    .rev()
                    .find(|c| c.backend == label)
                    .map(|c| c.seconds / c.runs.len().max(1) as f64 * (n as f64 / c.n as f64).powi(2));
                if let Some(p) = predicted.filter(|&p| p > args.cell_budget) {
                    let line = format!(
                        "{label} at n={n}: skipped, predicted {p:.0} s > --cell-budget {:.0} s",
                        args.cell_budget
                    );
                    say(&bar, line.clone());
                    journal.add_skipped(n, &label, &line)?;
                    skipped.push(line);
                    skip[j] = true;
                    bar.inc(1);
                    continue;
                }
                let cell = measure(job.backend, job.variant, sized(n), &params, frames, args.resolution, &devices)
                    .with_context(|| format!("{label} at n={n}"))?;
                let sub = cell.kernels.iter().find(|r| r.label == clothlab::core::timing::SUBSTEP);
                let frame = cell.frames.iter().find(|r| r.label == "frame");
                say(
                    &bar,
                    format!(
                        "{:<13} n={n:<5} substep {:>10.3} ms   frame {:>10.2} ms ({:.1} fps)   [{:.1} s]",
                        cell.backend,
                        sub.map(|r| r.median_ns / 1e6).unwrap_or(f64::NAN),
                        frame.map(|r| r.median_ns / 1e6).unwrap_or(f64::NAN),
                        frame.map(|r| 1e9 / r.median_ns).unwrap_or(f64::NAN),
                        cell.seconds
                    ),
                );
                journal.add_cell(n, &label, round, &cell)?;
                runs[j].push(cell);
                bar.inc(1);
            }
        }
        for (job, list) in jobs.iter().zip(runs) {
            if let Some((index, rung, Some(why))) = &job.rung {
                ladder.push(job.ladder_cell(*index, rung, n, &job.label(), &params, Some(why.clone()))?);
                continue;
            }
            let Some(cell) = Cell::merge(list) else { continue };
            if let Some((index, rung, None)) = &job.rung {
                ladder.push(job.ladder_cell(*index, rung, n, &cell.backend, &params, None)?);
            }
            cells.push(cell);
        }
        if interrupted {
            break 'sizes;
        }
    }

    // Fresh devices, never drawn on (lavapipe's timestamps, see run_cell).
    let mut overhead: Vec<(String, String, Vec<OverheadRow>)> = Vec::new();
    if !args.no_overhead && !interrupted {
        for api in ["wgpu", "wgpu-gl", "vulkan", "gl"] {
            let present = match api {
                "wgpu" => devices.wgpu.is_some(),
                "wgpu-gl" => devices.wgpu_gl.is_some(),
                "vulkan" => devices.vulkan.is_some(),
                _ => devices.gl.is_some(),
            };
            if !present || journal::stopping() {
                continue;
            }
            bar.set_message(format!("API overhead: {api}"));
            let (adapter, rows) = match journal.overhead(api) {
                Some(done) => {
                    overhead.push((api.to_owned(), done.0, done.1));
                    bar.inc(1);
                    continue;
                }
                None => clothlab::bench::overheads(api, &overhead_plan, &devices)?,
            };
            journal.add_overhead(api, &adapter, &rows)?;
            overhead.push((api.to_owned(), adapter, rows));
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    // A stop during the overhead benchmarks leaves every cell measured, not every API's
    // overhead (a stop during the last cell, with nothing after it, interrupts nothing).
    let apis = usize::from(devices.wgpu.is_some())
        + usize::from(devices.wgpu_gl.is_some())
        + usize::from(devices.vulkan.is_some())
        + usize::from(devices.gl.is_some());
    let overhead_missing = !args.no_overhead && overhead.len() < apis;
    let interrupted = (interrupted || journal::stopping() && overhead_missing).then(|| {
        if done_cells == total_cells {
            format!("after all {total_cells} cells, before every API's overhead benchmarks")
        } else {
            format!("after {done_cells} of {total_cells} cells")
        }
    });

    let mut results = results::Results::new(results::Inputs {
        machine,
        wgpu_adapter: devices.wgpu.as_ref().map(|c| c.describe()),
        vulkan_adapter: devices.vulkan.as_ref().map(|d| d.name().to_owned()),
        gl_adapter: devices.gl.clone(),
        cpu_simd: clothlab::bench::cpu_path_label(),
        params: params.clone(),
        scene: scene_label.clone(),
        frames,
        warmup_frames: WARMUP_FRAMES,
        resolution: args.resolution,
        plan: overhead_plan,
        cells,
        overhead,
        skipped,
        notes,
        seconds: started.elapsed().as_secs_f64() + resumed_seconds,
        command,
        ladder,
        interrupted,
    });
    results.peak_gbps = args.peak_gbps;
    let files = output::write_all(&results, &args.out)?;
    journal.finish(results.interrupted.is_none())?;
    for f in &files {
        outln!("wrote {}", f.display())?;
    }
    let failed: Vec<&results::Check> = results.checks.iter().filter(|c| !c.ok).collect();
    for c in &failed {
        eprintln!(
            "error: {} at n={} ended {:.2e} m from {} (bound {:.1e} m): not the same workload",
            c.backend, c.n, c.max_dev_m, c.reference, c.bound_m
        );
    }
    if let Some(what) = &results.interrupted {
        eprintln!(
            "interrupted {what}: the report holds what was measured; `clothlab bench --resume {}` with the same options measures the rest",
            args.out.display()
        );
        return Ok(ExitCode::from(130));
    }
    Ok(if failed.is_empty() { ExitCode::SUCCESS } else { ExitCode::FAILURE })
}

/// What one cell of every size runs: a backend, with a variant for a GPU one; on the
/// ladder, the rung (index, name, why it is skipped).
struct Job {
    backend: Backend,
    variant: Option<Variant>,
    rung: Option<(usize, String, Option<String>)>,
}

impl Job {
    /// The name its cells get: the solver's (`vulkan-naive+submit=frame`), or the backend's.
    fn label(&self) -> String {
        match (self.variant, self.backend.api()) {
            (Some(v), Some(api)) => v.solver_name(api.name()),
            _ => self.backend.name().to_string(),
        }
    }

    /// The ladder's record of this job at size `n`.
    fn ladder_cell(
        &self,
        index: usize,
        rung: &str,
        n: u32,
        backend: &str,
        params: &SimParams,
        skipped: Option<String>,
    ) -> Result<LadderCell> {
        let v = self.variant.context("a ladder job has a variant")?;
        let (dispatches, bytes) = clothlab::bench::recipe_traffic(&v, n, params)?;
        Ok(LadderCell {
            api: self.backend.api().map_or("cpu", Api::name).into(),
            n,
            index,
            rung: rung.to_string(),
            backend: backend.to_string(),
            switches: v.switches(),
            skipped,
            dispatches,
            bytes,
        })
    }
}
