//! `bench`'s default mode: every backend (or with `--ladder` every rung of each GPU API's
//! ladder and the thesis preset) at every size, `--repeat` rounds interleaved, resumable
//! from its journal; then the API-overhead micro-benchmarks; the results written as
//! CSV, JSON, a report and plots.

use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clothlab_core::timing::{OverheadPlan, OverheadRow};
use clothlab_core::{ClothState, Scene, SimParams};
use clothlab_engine::recipe::{bytes_moved, dispatches};
use clothlab_engine::variant::{Table, Variant, ladder as ladder_rungs};
use clothlab_gl::{GlCloth, GlRenderer};
use clothlab_vulkan::{Device, VkCloth, VulkanRenderer};
use clothlab_wgpu::{ClothSource, GpuContext, WgpuRenderer};
use indicatif::{ProgressBar, ProgressStyle};

use super::results::{self, Cell, LadderCell};
use super::{Request, WARMUP_FRAMES, cpu_label, journal, make_out_dir, output};
use crate::cli::{BenchArgs, Mode};
use crate::out::outln;
use crate::solvers::{AnySolver, Api, Backend, GpuSetup, Shared, make, vulkan_validation};

/// Particles per side of the lattice whose final positions are compared.
const CHECK_LATTICE: u32 = 5;
enum Painter {
    Wgpu(Box<(GpuContext, WgpuRenderer)>),
    Vulkan(Box<VulkanRenderer>),
    Gl(Box<GlRenderer>),
    None,
}

/// The devices opened once: they tell which APIs have an adapter, and draw the CPU
/// backends' frames. GPU cells and the overhead benchmarks get fresh devices (see
/// `run_cell`).
struct Devices {
    wgpu: Option<GpuContext>,
    vulkan: Option<Device>,
    /// The OpenGL context's description (a probe's; every GL cell opens its own).
    gl: Option<String>,
    /// wgpu on its GL backend, when wgpu's backend was not chosen and the default is
    /// another: its overhead benchmarks run as a fourth stack, `wgpu-gl`.
    wgpu_gl: Option<String>,
    wgpu_error: Option<String>,
    vulkan_error: Option<String>,
    gl_error: Option<String>,
}

impl Devices {
    fn open(need_wgpu: bool, need_vulkan: bool, need_gl: bool) -> Self {
        let (wgpu, wgpu_error) = if need_wgpu {
            match GpuContext::new() {
                Ok(c) => (Some(c), None),
                Err(e) => (None, Some(e.to_string())),
            }
        } else {
            (None, None)
        };
        let (vulkan, vulkan_error) = if need_vulkan {
            match Device::new(vulkan_validation()) {
                Ok(d) => (Some(d), None),
                Err(e) => (None, Some(e.to_string())),
            }
        } else {
            (None, None)
        };
        let (gl, gl_error) = if need_gl {
            match clothlab_gl::GlEngine::new() {
                Ok(e) => (Some(e.describe()), None),
                Err(e) => (None, Some(e.to_string())),
            }
        } else {
            (None, None)
        };
        let wgpu_gl = wgpu
            .as_ref()
            .filter(|c| clothlab_wgpu::chosen_backends().is_none() && c.info.backend != wgpu::Backend::Gl)
            .and_then(|_| GpuContext::with_backends(wgpu::Backends::GL).ok())
            .map(|c| c.describe());
        Self { wgpu, vulkan, gl, wgpu_gl, wgpu_error, vulkan_error, gl_error }
    }
}

fn is_vulkan(b: Backend) -> bool {
    matches!(b, Backend::VulkanNaive | Backend::Vulkan)
}

fn is_wgpu(b: Backend) -> bool {
    matches!(b, Backend::WgpuNaive | Backend::Wgpu)
}

fn is_gl(b: Backend) -> bool {
    matches!(b, Backend::GlNaive | Backend::Gl)
}

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
                let cell = run_cell(job, sized(n), &params, frames, args.resolution, &devices)
                    .with_context(|| format!("{label} at n={n}"))?;
                let sub = cell.kernels.iter().find(|r| r.label == clothlab_core::timing::SUBSTEP);
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
                None if api == "wgpu" => {
                    let ctx = GpuContext::new()?;
                    let rows =
                        clothlab_wgpu::overhead::measure(&ctx, &overhead_plan).context("wgpu overhead benchmarks")?;
                    (ctx.describe(), rows)
                }
                None if api == "wgpu-gl" => {
                    let ctx = GpuContext::with_backends(wgpu::Backends::GL)?;
                    let rows = clothlab_wgpu::overhead::measure(&ctx, &overhead_plan)
                        .context("wgpu-on-GL overhead benchmarks")?;
                    (ctx.describe(), rows)
                }
                None if api == "gl" => {
                    let rows = clothlab_gl::overhead::measure(&overhead_plan).context("OpenGL overhead benchmarks")?;
                    (devices.gl.clone().unwrap_or_default(), rows)
                }
                None => {
                    let dev = Device::new(vulkan_validation())?;
                    let rows = clothlab_vulkan::overhead::measure(&dev, &overhead_plan)
                        .context("Vulkan overhead benchmarks")?;
                    (format!("{} (Vulkan)", dev.name()), rows)
                }
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
        cpu_simd: clothlab_core::cpu::fused_path_label(),
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
        let (_, topo) = clothlab_core::build(&Scene::with_n(n), params)?;
        let how = clothlab_engine::recipe::Integration::of(params);
        let commands = clothlab_engine::recipe::recipe_for(&v, params.strain_iterations, how, &topo);
        // What runs once per frame (normals=frame) counts its share per substep in the
        // bytes; its dispatches (two per frame) are left out of the per-substep count.
        let end = clothlab_engine::recipe::frame_end(&v, how);
        let uniform = v.table == Table::Uniform;
        // With temporal blocking a recording of the commands advances `group` substeps.
        let group = clothlab_engine::recipe::dispatch_substeps(&v, how, params.strain_iterations, &topo);
        let bytes_of = |c: &[clothlab_engine::recipe::Command]| -> u64 {
            dispatches(c).map(|k| bytes_moved(k, &topo, uniform, params.strain_iterations, group)).sum()
        };
        Ok(LadderCell {
            api: self.backend.api().map_or("cpu", Api::name).into(),
            n,
            index,
            rung: rung.to_string(),
            backend: backend.to_string(),
            switches: v.switches(),
            skipped,
            dispatches: dispatches(&commands).count().div_ceil(group as usize),
            bytes: bytes_of(&commands) / u64::from(group) + bytes_of(&end) / u64::from(params.substeps.max(1)),
        })
    }
}

fn run_cell(
    job: &Job,
    scene: Scene,
    params: &SimParams,
    frames: u32,
    (width, height): (u32, u32),
    devices: &Devices,
) -> Result<Cell> {
    let t_cell = Instant::now();
    let n = scene.cloth.n;
    let p = params.clone();
    // A device of its own for every GPU cell (see below).
    let setup = GpuSetup { variant: job.variant.map(Into::into), ..GpuSetup::default() };
    let mut sim = make(job.backend, scene.clone(), p, &setup, &Shared::None)?;
    let (_, topo) = clothlab_core::build(&scene, params)?;
    let mut painter = match &sim {
        AnySolver::Wgpu(s, _) => {
            let ctx = s.engine().context();
            Painter::Wgpu(Box::new((ctx.clone(), WgpuRenderer::new(ctx, &scene, &topo, width, height)?)))
        }
        AnySolver::Vulkan(s, _) => {
            Painter::Vulkan(Box::new(VulkanRenderer::new(&s.engine().device(), &scene, &topo, width, height)?))
        }
        AnySolver::Gl(s) => Painter::Gl(Box::new(GlRenderer::new(s.engine().context(), &scene, &topo, width, height)?)),
        // The CPU solvers, drawn from their state uploaded.
        AnySolver::Cpu(_) => match (&devices.wgpu, &devices.vulkan) {
            (Some(ctx), _) => {
                Painter::Wgpu(Box::new((ctx.clone(), WgpuRenderer::new(ctx, &scene, &topo, width, height)?)))
            }
            (None, Some(dev)) => Painter::Vulkan(Box::new(VulkanRenderer::new(dev, &scene, &topo, width, height)?)),
            (None, None) => Painter::None,
        },
    };
    let adapter = match &sim {
        AnySolver::Cpu(_) => cpu_label(),
        gpu => gpu.adapter(),
    };
    let view = Mode::Triangles.view();

    // Nothing is drawn before the per-kernel table: on lavapipe, once a device has drawn,
    // its timestamps no longer bracket compute dispatches (llvmpipe then takes timestamp
    // queries through the rasterizer's scene, at the next flush), so every GPU cell runs
    // on a device of its own and draws only after its kernels were timed.
    for _ in 0..WARMUP_FRAMES {
        sim.get().step_frame()?;
    }
    // Per-kernel table.
    sim.get().set_kernel_timing(true);
    sim.get().reset_timings();
    for _ in 0..frames {
        sim.get().step_frame()?;
    }
    let kernels = sim.get().timings().rows;
    // Frame table: per-kernel timestamps off, each frame simulated, waited for, drawn
    // (after one unmeasured draw that builds the renderer's pipelines and shadow map).
    sim.get().set_kernel_timing(false);
    draw(&mut sim, &mut painter, &view)?;
    let mut rec = clothlab_core::TimingRecorder::new(frames as usize);
    for _ in 0..frames {
        let t = Instant::now();
        sim.get().step_frame()?;
        sim.finish()?;
        let t_sim = t.elapsed().as_nanos() as f64;
        let t = Instant::now();
        let drew = draw(&mut sim, &mut painter, &view)?;
        let t_render = t.elapsed().as_nanos() as f64;
        rec.record("sim", t_sim);
        if drew {
            rec.record("render", t_render);
        }
        rec.record("frame", t_sim + if drew { t_render } else { 0.0 });
    }
    let state = sim.get().state()?;
    Ok(Cell {
        backend: sim.get_ref().name().to_owned(),
        n,
        adapter,
        kernels,
        frames: rec.table().rows,
        probe: probe(&state),
        seconds: t_cell.elapsed().as_secs_f64(),
        runs: Vec::new(),
    })
}

/// Draws the cloth offscreen and waits for the picture; false when there is no renderer.
fn draw(sim: &mut AnySolver, painter: &mut Painter, view: &clothlab_core::View) -> Result<bool> {
    match (painter, sim) {
        (Painter::None, _) => return Ok(false),
        (Painter::Wgpu(p), AnySolver::Cpu(s)) => {
            let (ctx, r) = &mut **p;
            r.render(ctx, view, ClothSource::Cpu(s.state_ref()))?;
            ctx.wait_idle()?;
        }
        (Painter::Wgpu(p), AnySolver::Wgpu(s, _)) => {
            let (ctx, r) = &mut **p;
            let (pos, normal) = s.vertex_buffers();
            r.render(ctx, view, ClothSource::Gpu { pos, normal })?;
            ctx.wait_idle()?;
        }
        (Painter::Vulkan(r), AnySolver::Cpu(s)) => r.render(view, VkCloth::Cpu(s.state_ref()))?,
        (Painter::Gl(r), AnySolver::Gl(s)) => {
            let (&pos, &normal) = s.vertex_buffers();
            r.render(s.engine().context(), view, GlCloth::Gpu { pos, normal })?;
            // The picture finished, as the other APIs wait for theirs.
            s.finish()?;
        }
        (Painter::Vulkan(r), AnySolver::Vulkan(s, _)) => {
            let (pos, normal) = s.vertex_buffers();
            r.render(view, VkCloth::Gpu { pos, normal })?;
        }
        _ => bail!("a GPU solver's buffers are drawn by its own API"),
    }
    Ok(true)
}

/// Positions of a `CHECK_LATTICE`² lattice of particles, corners included; of a mesh
/// (`n = 0`), as many spread evenly over its particles, the first and last included.
fn probe(state: &ClothState) -> Vec<[f32; 3]> {
    let n = state.n as usize;
    let m = CHECK_LATTICE as usize;
    if n == 0 {
        let (count, last) = (m * m, state.pos.len().saturating_sub(1));
        return (0..count).map(|k| state.pos[k * last / (count - 1)]).map(|p| [p[0], p[1], p[2]]).collect();
    }
    let at = |k: usize| if n == 1 { 0 } else { k * (n - 1) / (m - 1) };
    let mut v = Vec::with_capacity(m * m);
    for j in 0..m {
        for i in 0..m {
            let p = state.pos[at(j) * n + at(i)];
            v.push([p[0], p[1], p[2]]);
        }
    }
    v
}
