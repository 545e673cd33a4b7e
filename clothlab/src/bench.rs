//! Measurement as data: one backend × size cell of `clothlab bench` (per-kernel times,
//! then whole frames with an offscreen render each, and the final positions of a lattice
//! of particles), and [`cells`], the backends at each size as a list of cells. The
//! command's reports, the ladder, `--repeat`'s rounds and the API-overhead benchmarks are
//! built on these by the command line.
//!
//! Every cell runs the same workload: the scene and parameters asked for, [`WARMUP_FRAMES`]
//! frames, then `frames` frames with per-kernel timing on (the kernel table), then
//! `frames` frames with it off, each followed by an offscreen render (the frame table).

use std::time::Instant;

use anyhow::{Result, bail};
use clothlab_core::{ClothState, RenderMode, Scene, SimParams};
use clothlab_engine::Variant;
use clothlab_gl::{GlCloth, GlRenderer};
use clothlab_vulkan::{Device, VkCloth, VulkanRenderer};
use clothlab_wgpu::{ClothSource, GpuContext, WgpuRenderer};
use serde::{Deserialize, Serialize};

use crate::backend::{AnySolver, Backend, GpuSetup, Shared, make, vulkan_validation};

/// Unmeasured frames at the start of every cell (pipelines, caches, clocks, the cloth's
/// first fall).
pub const WARMUP_FRAMES: u32 = 3;

/// What the CPU solvers run a Verlet substep on here (the fused sweep at the instruction
/// set chosen, or why not), for reports.
pub fn cpu_path_label() -> String {
    clothlab_cpu::fused_path_label()
}

/// The CPU in one line: model and logical cores.
pub fn cpu_label() -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, m)| m.trim().to_owned())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_owned());
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    format!("{model}, {cores} threads")
}

/// One backend × size measurement.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Cell {
    /// Backend name.
    pub backend: String,
    /// Particles per side.
    pub n: u32,
    /// Where it ran: the adapter, or the CPU.
    pub adapter: String,
    /// Per-kernel table (per substep; `frame`, `cpu record`, `cpu submit` per frame).
    pub kernels: Vec<clothlab_core::TimingRow>,
    /// Whole frames with per-kernel timing off: `sim` (substeps, until the GPU is done),
    /// `render` (offscreen, until done) and `frame` (both).
    pub frames: Vec<clothlab_core::TimingRow>,
    /// Positions of the check lattice after the run.
    pub probe: Vec<[f32; 3]>,
    /// Seconds the cell took.
    pub seconds: f64,
    /// The substep median of every round (`--repeat`), ns, in the order run.
    pub runs: Vec<f64>,
    /// With the contact between triangles: its searches for pairs a frame over the
    /// per-kernel frames, full and partial (docs/contact.md, "How often it searches").
    #[serde(default)]
    pub searches: Option<[f64; 2]>,
}

impl Cell {
    /// One cell from the rounds of one job at one size: per label the median of the
    /// rounds' medians, the smallest minimum and the largest maximum, the samples summed;
    /// the probe of the first round (each is checked against the reference alike).
    pub fn merge(rounds: Vec<Cell>) -> Option<Cell> {
        let first = rounds.first()?.clone();
        let merge_rows = |pick: &dyn Fn(&Cell) -> &Vec<clothlab_core::TimingRow>| -> Vec<clothlab_core::TimingRow> {
            pick(&first)
                .iter()
                .map(|row| {
                    let same: Vec<&clothlab_core::TimingRow> =
                        rounds.iter().filter_map(|c| pick(c).iter().find(|r| r.label == row.label)).collect();
                    let mut medians: Vec<f64> = same.iter().map(|r| r.median_ns).collect();
                    medians.sort_by(f64::total_cmp);
                    let m = medians.len();
                    let median = if m % 2 == 1 { medians[m / 2] } else { (medians[m / 2 - 1] + medians[m / 2]) / 2.0 };
                    clothlab_core::TimingRow {
                        label: row.label.clone(),
                        samples: same.iter().map(|r| r.samples).sum(),
                        median_ns: median,
                        min_ns: same.iter().map(|r| r.min_ns).fold(f64::INFINITY, f64::min),
                        max_ns: same.iter().map(|r| r.max_ns).fold(0.0, f64::max),
                    }
                })
                .collect()
        };
        let runs = rounds
            .iter()
            .filter_map(|c| c.kernels.iter().find(|r| r.label == clothlab_core::timing::SUBSTEP).map(|r| r.median_ns))
            .collect();
        Some(Cell {
            kernels: merge_rows(&|c| &c.kernels),
            frames: merge_rows(&|c| &c.frames),
            seconds: rounds.iter().map(|c| c.seconds).sum(),
            runs,
            ..first
        })
    }
}

/// Particles per side of the lattice whose final positions are compared.
pub const CHECK_LATTICE: u32 = 5;
/// What draws a cell's frames: the solver's own API, or (a CPU solver) wgpu or Vulkan.
enum Painter {
    Wgpu(Box<(GpuContext, WgpuRenderer)>),
    Vulkan(Box<VulkanRenderer>),
    Gl(Box<GlRenderer>),
    None,
}

/// The devices opened once: they tell which APIs have an adapter, and draw the CPU
/// backends' frames. GPU cells and the overhead benchmarks get fresh devices (see
/// [`measure`]).
pub struct Devices {
    /// wgpu's context (draws the CPU backends' frames).
    pub wgpu: Option<GpuContext>,
    /// A Vulkan device (draws the CPU backends' frames where wgpu has none).
    pub vulkan: Option<Device>,
    /// The OpenGL context's description (a probe's; every GL cell opens its own).
    pub gl: Option<String>,
    /// wgpu on its GL backend, when wgpu's backend was not chosen and the default is
    /// another: its overhead benchmarks run as a fourth stack, `wgpu-gl`.
    pub wgpu_gl: Option<String>,
    /// Why wgpu has no adapter.
    pub wgpu_error: Option<String>,
    /// Why Vulkan has no device.
    pub vulkan_error: Option<String>,
    /// Why OpenGL has no context.
    pub gl_error: Option<String>,
}

impl Devices {
    /// Opens what is needed: wgpu's, Vulkan's and GL's devices (a failure kept as its
    /// message).
    pub fn open(need_wgpu: bool, need_vulkan: bool, need_gl: bool) -> Self {
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

/// Whether `b` runs on raw Vulkan.
pub fn is_vulkan(b: Backend) -> bool {
    matches!(b, Backend::VulkanNaive | Backend::Vulkan)
}

/// Whether `b` runs on wgpu.
pub fn is_wgpu(b: Backend) -> bool {
    matches!(b, Backend::WgpuNaive | Backend::Wgpu)
}

/// Whether `b` runs on raw OpenGL.
pub fn is_gl(b: Backend) -> bool {
    matches!(b, Backend::GlNaive | Backend::Gl)
}

/// Measures `backend` (with `variant`, a GPU one; else its preset) on `scene`: warm-up
/// frames, `frames` frames timed kernel by kernel, then `frames` frames timed whole with
/// an offscreen render of `resolution` each (the CPU backends drawn through `devices`).
pub fn measure(
    backend: Backend,
    variant: Option<Variant>,
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
    let setup = GpuSetup { variant: variant.map(Into::into), ..GpuSetup::default() };
    let mut sim = make(backend, scene.clone(), p, &setup, &Shared::None)?;
    let topo = sim.topology();
    let mut painter = match &sim {
        AnySolver::Wgpu(s, _) => {
            let ctx = s.engine().context();
            Painter::Wgpu(Box::new((ctx.clone(), WgpuRenderer::new(ctx, &scene, topo, width, height)?)))
        }
        AnySolver::Vulkan(s, _) => {
            Painter::Vulkan(Box::new(VulkanRenderer::new(&s.engine().device(), &scene, topo, width, height)?))
        }
        AnySolver::Gl(s) => Painter::Gl(Box::new(GlRenderer::new(s.engine().context(), &scene, topo, width, height)?)),
        // The CPU solvers, drawn from their state uploaded.
        AnySolver::Cpu(_) => match (&devices.wgpu, &devices.vulkan) {
            (Some(ctx), _) => {
                Painter::Wgpu(Box::new((ctx.clone(), WgpuRenderer::new(ctx, &scene, topo, width, height)?)))
            }
            (None, Some(dev)) => Painter::Vulkan(Box::new(VulkanRenderer::new(dev, &scene, topo, width, height)?)),
            (None, None) => Painter::None,
        },
    };
    let adapter = match &sim {
        AnySolver::Cpu(_) => cpu_label(),
        gpu => gpu.adapter(),
    };
    let view = crate::render::default_view(RenderMode::Triangles);

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
    let counts = |sim: &AnySolver| sim.get_ref().contact_stats().map(|c| [c.searches as f64, c.refreshes as f64]);
    let before = counts(&sim);
    for _ in 0..frames {
        sim.get().step_frame()?;
    }
    let searches =
        counts(&sim).map(|after| [0, 1].map(|k| (after[k] - before.map_or(0.0, |b| b[k])) / frames.max(1) as f64));
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
        searches,
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
pub fn probe(state: &ClothState) -> Vec<[f32; 3]> {
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

/// What [`cells`] measures.
#[derive(Debug, Clone)]
pub struct BenchOptions {
    /// The backends, in order (each once); a GPU one without an adapter is skipped with a
    /// note in [`BenchRun::skipped`].
    pub backends: Vec<Backend>,
    /// Grid sizes, particles per side (2 ..= 4096; a mesh scene is measured once).
    pub sizes: Vec<u32>,
    /// Frames timed kernel by kernel, and as many again timed whole (1 ..= 100000).
    pub frames: u32,
    /// The offscreen render target of the frame table, pixels.
    pub resolution: (u32, u32),
    /// The scene and its parameters.
    pub physics: crate::Physics,
}

impl Default for BenchOptions {
    fn default() -> Self {
        Self {
            backends: vec![Backend::Cpu, Backend::CpuPar],
            sizes: vec![64],
            frames: 30,
            resolution: (640, 360),
            physics: crate::Physics::default(),
        }
    }
}

/// The cells [`cells`] measured, and what it skipped.
#[derive(Debug, Clone, Default)]
pub struct BenchRun {
    /// One cell per size × backend, sizes outermost.
    pub cells: Vec<Cell>,
    /// Each backend skipped, with why (no adapter for its API).
    pub skipped: Vec<String>,
}

/// Measures every backend of `opts` at every size ([`measure`]); the arguments are all
/// checked before anything runs.
pub fn cells(opts: &BenchOptions) -> Result<BenchRun> {
    let mut sizes = opts.sizes.clone();
    if sizes.is_empty() {
        bail!("sizes is empty: give at least one grid size");
    }
    if let Some(&n) = sizes.iter().find(|&&n| !(2..=4096).contains(&n)) {
        bail!("invalid size {n}: grid sizes must be in 2 ..= 4096");
    }
    sizes.sort_unstable();
    sizes.dedup();
    if !(1..=100_000).contains(&opts.frames) {
        bail!("invalid frames {}: must be in 1 ..= 100000", opts.frames);
    }
    let (w, h) = opts.resolution;
    if !(16..=8192).contains(&w) || !(16..=8192).contains(&h) {
        bail!("invalid resolution {w}x{h}: width and height must be in 16 ..= 8192");
    }
    let mut backends = Vec::new();
    for &b in &opts.backends {
        if !backends.contains(&b) {
            backends.push(b);
        }
    }
    if backends.is_empty() {
        bail!("backends is empty: name at least one backend");
    }
    let setup = opts.physics.setup(None, sizes[0])?;
    if setup.scene.cloth.is_mesh() {
        sizes.truncate(1);
    }
    let sized = |n: u32| {
        let mut s = setup.scene.clone();
        if !s.cloth.is_mesh() {
            s.cloth.n = n;
        }
        s
    };
    for &n in &sizes {
        clothlab_core::cloth::check_params(&sized(n), &setup.params)?;
    }
    let devices = Devices::open(
        backends.iter().any(|&b| is_wgpu(b) || !b.is_gpu()),
        backends.iter().any(|&b| is_vulkan(b)),
        backends.iter().any(|&b| is_gl(b)),
    );
    let mut run = BenchRun::default();
    backends.retain(|&b| {
        let missing = if is_wgpu(b) {
            devices.wgpu_error.as_ref()
        } else if is_vulkan(b) {
            devices.vulkan_error.as_ref()
        } else if is_gl(b) {
            devices.gl_error.as_ref()
        } else {
            None
        };
        if let Some(e) = missing {
            run.skipped.push(format!("{}: no adapter ({e})", b.name()));
        }
        missing.is_none()
    });
    for &n in &sizes {
        for &b in &backends {
            let cell = measure(b, None, sized(n), &setup.params, opts.frames, opts.resolution, &devices)
                .map_err(|e| e.context(format!("{} at n={n}", b.name())))?;
            run.cells.push(cell);
        }
    }
    Ok(run)
}

/// The API-overhead micro-benchmarks (`OverheadPlan`: an empty submit and wait, dependent
/// and independent dispatches, uploads, readbacks) of one stack by name — `wgpu` (its
/// default backend), `wgpu-gl` (wgpu on its GL backend), `vulkan`, `gl` — on a fresh
/// device of its own, never drawn on (GL's described as `devices` found it): its
/// adapter's description and the rows.
pub fn overheads(
    api: &str,
    plan: &clothlab_core::timing::OverheadPlan,
    devices: &Devices,
) -> Result<(String, Vec<clothlab_core::timing::OverheadRow>)> {
    use anyhow::Context as _;
    Ok(match api {
        "wgpu" => {
            let ctx = GpuContext::new()?;
            let rows = clothlab_wgpu::overhead::measure(&ctx, plan).context("wgpu overhead benchmarks")?;
            (ctx.describe(), rows)
        }
        "wgpu-gl" => {
            let ctx = GpuContext::with_backends(wgpu::Backends::GL)?;
            let rows = clothlab_wgpu::overhead::measure(&ctx, plan).context("wgpu-on-GL overhead benchmarks")?;
            (ctx.describe(), rows)
        }
        "gl" => {
            let rows = clothlab_gl::overhead::measure(plan).context("OpenGL overhead benchmarks")?;
            (devices.gl.clone().unwrap_or_default(), rows)
        }
        "vulkan" => {
            let dev = Device::new(vulkan_validation())?;
            let rows = clothlab_vulkan::overhead::measure(&dev, plan).context("Vulkan overhead benchmarks")?;
            (format!("{} (Vulkan)", dev.name()), rows)
        }
        other => bail!("no overhead benchmarks for {other:?}: wgpu, wgpu-gl, vulkan or gl"),
    })
}

/// What a variant's recipe moves and dispatches a substep on an `n` × `n` grid with
/// `params`: its dispatches a substep and its bytes read and written a substep (the
/// frame's end counted by its share; with temporal blocking a recording advances several
/// substeps, each counted by its share), as `clothlab bench --ladder` reports them.
pub fn recipe_traffic(variant: &Variant, n: u32, params: &SimParams) -> Result<(usize, u64)> {
    use clothlab_engine::recipe::{
        Command, Integration, bytes_moved, dispatch_substeps, dispatches, frame_end, recipe_for,
    };
    let (_, topo) = clothlab_core::build(&Scene::with_n(n), params)?;
    let how = Integration::of(params);
    let commands = recipe_for(variant, params.strain_iterations, how, &topo);
    // What runs once per frame (normals=frame) counts its share per substep in the
    // bytes; its dispatches (two per frame) are left out of the per-substep count.
    let end = frame_end(variant, how);
    let uniform = variant.table == clothlab_engine::variant::Table::Uniform;
    let group = dispatch_substeps(variant, how, params.strain_iterations, &topo);
    let bytes_of = |c: &[Command]| -> u64 {
        dispatches(c).map(|k| bytes_moved(k, &topo, uniform, params.strain_iterations, group)).sum()
    };
    Ok((
        dispatches(&commands).count().div_ceil(group as usize),
        bytes_of(&commands) / u64::from(group) + bytes_of(&end) / u64::from(params.substeps.max(1)),
    ))
}
