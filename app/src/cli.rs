//! Argument parsing and the headless subcommands.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand, ValueEnum};
use clothlab_core::layout::Buf;
use clothlab_core::stats::{summarize, write_json, write_obj};
use clothlab_core::timing::SUBSTEP;
use clothlab_core::validate::validate_rollout;
use clothlab_core::{CpuSolver, Exec, Scene, SimParams, Solver};
use clothlab_engine::recipe::Command as StepCommand;
use clothlab_engine::validate::{KernelRunner, bisect, validate_kernels};
use clothlab_engine::{KernelRef, Variant};
use clothlab_vulkan::{SpringTable, StatsMode, VkCloth, VulkanOptions, VulkanRenderer, VulkanSolver};
use clothlab_wgpu::{ClothSource, WgpuRenderer, WgpuSolver};

#[derive(Parser)]
#[command(name = "clothlab", version, about = "Interactive, GPU-accelerated cloth simulation testbed")]
struct Cli {
    /// What to do; without one, the interactive app opens (`run`).
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Open the interactive app (the default): the cloth live, on any backend and API.
    Run(RunArgs),
    /// Simulate headless and print a summary.
    Sim(SimArgs),
    /// Check every GPU kernel and a rollout on each GPU backend against the CPU reference.
    Validate(ValidateArgs),
    /// Simulate headless, then render the scene to a PNG (no window, no display).
    Render(RenderArgs),
    /// Measure every backend: per-kernel times, time per frame and fps against grid size,
    /// and the API overhead of wgpu vs Vulkan; writes CSV, JSON, a report and plots.
    Bench(crate::bench::BenchArgs),
}

/// Cloth render modes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Mode {
    /// One point per particle.
    Points,
    /// Triangle edges.
    Lines,
    /// Lit, textured, shadowed triangles.
    Triangles,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// Solver backend.
    #[arg(long, value_enum, default_value_t = Backend::Wgpu)]
    backend: Backend,
    /// Particles per side of the cloth.
    #[arg(long, default_value_t = 100)]
    n: u32,
    /// Frames to simulate before the picture (of `substeps` substeps each).
    #[arg(long, default_value_t = 120)]
    frames: u32,
    /// How the cloth is drawn.
    #[arg(long, value_enum, default_value_t = Mode::Triangles)]
    mode: Mode,
    /// Image width, pixels.
    #[arg(long, default_value_t = 960)]
    width: u32,
    /// Image height, pixels.
    #[arg(long, default_value_t = 640)]
    height: u32,
    /// Output PNG file.
    #[arg(long)]
    out: PathBuf,
    /// Graphics API of the renderer: wgpu, or raw Vulkan. Default: Vulkan for the Vulkan
    /// solvers (drawn from their buffers), wgpu for the others (CPU solvers upload a frame
    /// to either).
    #[arg(long, value_enum)]
    api: Option<Api>,
}

/// Graphics APIs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Api {
    /// wgpu (Vulkan, Metal, DX12 or GL underneath).
    Wgpu,
    /// Raw Vulkan through ash.
    Vulkan,
}

#[derive(clap::Args)]
struct ValidateArgs {
    /// GPU backends to check (comma-separated).
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = [Backend::WgpuNaive, Backend::Wgpu, Backend::VulkanNaive, Backend::Vulkan])]
    backends: Vec<Backend>,
    /// Particles per side for the kernel checks and the rollout (2 ..= 1024).
    #[arg(long, default_value_t = 64)]
    n: u32,
    /// Substeps of the rollout (rounded up to whole frames).
    #[arg(long, default_value_t = 200)]
    steps: u32,
    /// Instead of the checks: a rollout in which every substep runs its first k
    /// dispatches on the CPU engine and the rest on the GPU, for every k, naming the first
    /// kernel after which the GPU leaves the rollout bound (`--steps` substeps of an
    /// `--n` cloth; n = 32 keeps it quick).
    #[arg(long)]
    bisect: bool,
}

#[derive(clap::Args, Debug)]
struct RunArgs {
    /// Graphics API of the window.
    #[arg(long, value_enum, default_value_t = Api::Wgpu)]
    api: Api,
    /// Solver (default: the optimized GPU solver of the API).
    #[arg(long, value_enum)]
    backend: Option<Backend>,
    /// Particles per side of the cloth (10 ..= 1024 in the app).
    #[arg(long, default_value_t = 64)]
    n: u32,
    /// Quit after this many frames (for tests and screenshots).
    #[arg(long)]
    frames: Option<u64>,
    /// Save a PNG of the window (panels included) after `--frames` frames.
    #[arg(long)]
    screenshot: Option<PathBuf>,
    /// Window width, pixels.
    #[arg(long, default_value_t = 1280)]
    width: u32,
    /// Window height, pixels.
    #[arg(long, default_value_t = 800)]
    height: u32,
    /// Test hook: from frame 5 on, grab the cloth under its middle with the cursor tool
    /// and drag it upwards, printing what was grabbed and where it went.
    #[arg(long, hide = true)]
    drag_test: bool,
    /// Test hook: halfway through `--frames`, switch to the other graphics API.
    #[arg(long, hide = true)]
    switch_api: bool,
}

impl Default for RunArgs {
    fn default() -> Self {
        Self {
            api: Api::Wgpu,
            backend: None,
            n: 64,
            frames: None,
            screenshot: None,
            width: 1280,
            height: 800,
            drag_test: false,
            switch_api: false,
        }
    }
}

fn run_app(args: RunArgs) -> Result<ExitCode> {
    if !(10..=1024).contains(&args.n) {
        bail!("invalid --n {}: the app takes 10 ..= 1024 particles per side", args.n);
    }
    let backend = args.backend.unwrap_or(match args.api {
        Api::Wgpu => Backend::Wgpu,
        Api::Vulkan => Backend::Vulkan,
    });
    crate::gui::run(crate::gui::RunOptions {
        api: args.api,
        backend,
        n: args.n,
        frames: args.frames,
        screenshot: args.screenshot,
        size: (args.width, args.height),
        drag_test: args.drag_test,
        switch_api: args.switch_api,
    })
}

/// Solver backends.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Backend {
    /// CPU, one thread (the thesis's CPU variant).
    Cpu,
    /// CPU, rayon threads (the thesis's OpenMP variant).
    CpuPar,
    /// wgpu, the direct port: a dispatch per kernel, atomics (the thesis's CUDA port).
    WgpuNaive,
    /// wgpu, optimized: fused kernels, gathers, one submission per frame.
    Wgpu,
    /// Raw Vulkan, the naive recipe (same kernels as wgpu-naive).
    VulkanNaive,
    /// Raw Vulkan, the optimized recipe with push constants.
    Vulkan,
}

impl Backend {
    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Backend::Cpu => "cpu",
            Backend::CpuPar => "cpu-par",
            Backend::WgpuNaive => "wgpu-naive",
            Backend::Wgpu => "wgpu",
            Backend::VulkanNaive => "vulkan-naive",
            Backend::Vulkan => "vulkan",
        }
    }
}

/// Whether the Vulkan backends run with the Khronos validation layer: in debug builds,
/// or when CLOTHLAB_VALIDATION=1.
pub fn vulkan_validation() -> bool {
    cfg!(debug_assertions) || std::env::var("CLOTHLAB_VALIDATION").as_deref() == Ok("1")
}

#[derive(clap::Args)]
struct SimArgs {
    /// Solver backend.
    #[arg(long, value_enum, default_value_t = Backend::Cpu)]
    backend: Backend,
    /// Particles per side of the cloth (2 ..= 4096).
    #[arg(long, default_value_t = 100)]
    n: u32,
    /// Substeps to simulate (rounded up to whole frames of `substeps` each).
    #[arg(long, default_value_t = 1000)]
    steps: u64,
    /// Override a simulation parameter, e.g. `--set damping=0.001 --set wind=[2,0,1]`
    /// (names as in `SimParams`; see docs/parameters.md).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    set: Vec<String>,
    /// Write the final state: `.obj` (mesh with normals and uvs) or `.json` (full state).
    #[arg(long)]
    out: Option<PathBuf>,
    #[command(flatten)]
    vulkan: VulkanArgs,
}

/// Options of the Vulkan backends.
#[derive(clap::Args, Clone, Copy, Debug, Default)]
pub struct VulkanArgs {
    /// Vulkan only: per-substep statistics (max strain, kinetic energy) on the GPU, by
    /// subgroup reductions or by atomics.
    #[arg(long, value_enum, default_value_t = StatsArg::Off)]
    pub stats: StatsArg,
    /// Vulkan only: where the gathers read the spring table.
    #[arg(long, value_enum, default_value_t = TableArg::Interior)]
    pub table: TableArg,
}

/// `--stats` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, ValueEnum)]
pub enum StatsArg {
    /// Not computed.
    #[default]
    Off,
    /// Atomics from every invocation.
    Atomics,
    /// Subgroup reductions, no atomics.
    Subgroups,
}

/// `--table` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, ValueEnum)]
pub enum TableArg {
    /// Uniform constants in the interior, storage buffers at the border.
    #[default]
    Interior,
    /// Read-only storage buffers everywhere.
    Storage,
    /// A sampled image (texture memory) everywhere.
    Image,
}

impl VulkanArgs {
    /// The Vulkan solver's options.
    pub fn options(self) -> VulkanOptions {
        VulkanOptions {
            validation: vulkan_validation(),
            stats: match self.stats {
                StatsArg::Off => StatsMode::Off,
                StatsArg::Atomics => StatsMode::Atomics,
                StatsArg::Subgroups => StatsMode::Subgroups,
            },
            table: match self.table {
                TableArg::Interior => SpringTable::Interior,
                TableArg::Storage => SpringTable::Storage,
                TableArg::Image => SpringTable::Image,
            },
        }
    }

    fn is_default(self) -> bool {
        self.stats == StatsArg::Off && self.table == TableArg::Interior
    }
}

/// Most substeps one `sim` run may ask for.
const MAX_STEPS: u64 = 100_000_000;

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
    match cli.command.unwrap_or(Command::Run(RunArgs::default())) {
        Command::Run(args) => run_app(args),
        Command::Sim(args) => sim(args),
        Command::Validate(args) => validate(args),
        Command::Render(args) => render(args),
        Command::Bench(args) => crate::bench::bench(args),
    }
}

/// Applies `NAME=VALUE` overrides to `params` through its serde form, so every field is
/// reachable and an unknown name or a value of the wrong type is refused.
pub fn apply_overrides(params: &SimParams, sets: &[String]) -> Result<SimParams> {
    let mut value = serde_json::to_value(params)?;
    for s in sets {
        let Some((name, raw)) = s.split_once('=') else {
            bail!("--set expects NAME=VALUE, got `{s}`");
        };
        let name = name.trim();
        let obj = value.as_object_mut().context("parameters are not an object")?;
        let Some(slot) = obj.get_mut(name) else {
            let mut known: Vec<&String> = obj.keys().collect();
            known.sort();
            let known: Vec<&str> = known.iter().map(|s| s.as_str()).collect();
            bail!("unknown parameter `{name}` (known: {})", known.join(", "));
        };
        let parsed: serde_json::Value = match raw.trim() {
            // JSON has no NaN or infinities; name them so that validate() refuses them
            // with its own message instead of a parse error.
            "nan" | "NaN" | "inf" | "-inf" | "infinity" | "-infinity" => {
                bail!("invalid parameter `{name}` = {raw}: must be a finite number")
            }
            r => serde_json::from_str(r).with_context(|| format!("`{name}`: cannot parse `{r}`"))?,
        };
        *slot = parsed;
    }
    let out: SimParams = serde_json::from_value(value).context("parameter of the wrong type")?;
    out.validate()?;
    Ok(out)
}

pub fn make_solver(backend: Backend, scene: Scene, params: SimParams) -> Result<Box<dyn Solver>> {
    make_solver_with(backend, scene, params, VulkanArgs::default())
}

/// [`make_solver`] with the Vulkan backends' options (refused for the others).
pub fn make_solver_with(
    backend: Backend,
    scene: Scene,
    params: SimParams,
    vulkan: VulkanArgs,
) -> Result<Box<dyn Solver>> {
    let is_vulkan = matches!(backend, Backend::VulkanNaive | Backend::Vulkan);
    if !is_vulkan && !vulkan.is_default() {
        bail!("--stats and --table apply to the Vulkan backends (vulkan-naive, vulkan) only");
    }
    Ok(match backend {
        Backend::Cpu => Box::new(CpuSolver::new(Exec::Serial, scene, params)?),
        Backend::CpuPar => Box::new(CpuSolver::new(Exec::Parallel, scene, params)?),
        Backend::WgpuNaive => Box::new(WgpuSolver::new(Variant::Naive, scene, params)?),
        Backend::Wgpu => Box::new(WgpuSolver::new(Variant::Optimized, scene, params)?),
        Backend::VulkanNaive => Box::new(VulkanSolver::with_options(Variant::Naive, scene, params, vulkan.options())?),
        Backend::Vulkan => Box::new(VulkanSolver::with_options(Variant::Optimized, scene, params, vulkan.options())?),
    })
}

fn sim(args: SimArgs) -> Result<ExitCode> {
    let params = apply_overrides(&SimParams::default(), &args.set)?;
    let scene = Scene::with_n(args.n);
    scene.validate()?;
    if args.steps == 0 || args.steps > MAX_STEPS {
        bail!("invalid --steps {}: must be in 1 ..= {MAX_STEPS}", args.steps);
    }
    // Open the output before simulating, so a bad path fails at once, not after the run.
    let out = match &args.out {
        Some(path) => {
            let format = out_format(path)?;
            let file = File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
            Some((path, format, BufWriter::new(file)))
        }
        None => None,
    };
    let frames = args.steps.div_ceil(params.substeps as u64);
    let substeps = frames * params.substeps as u64;
    let mut solver = make_solver_with(args.backend, scene.clone(), params, args.vulkan)?;
    let t0 = Instant::now();
    for _ in 0..frames {
        solver.step_frame()?;
    }
    let wall = t0.elapsed();
    let state = solver.state()?;
    let (_, topo) = clothlab_core::build(&scene, solver.params())?;
    let summary = summarize(&state, &topo);
    let np = scene.num_particles() as f64;
    let per_substep =
        solver.timings().get(SUBSTEP).map(|r| r.median_ns).unwrap_or(wall.as_nanos() as f64 / substeps as f64);

    println!("backend        {}", solver.name());
    println!("grid           {n}x{n} ({np} particles)", n = args.n);
    println!("substeps       {substeps} ({frames} frames of {})", solver.params().substeps);
    println!("wall time      {:.3} s", wall.as_secs_f64());
    println!("time/substep   {:.1} us median ({:.2} ns per particle-substep)", per_substep / 1e3, per_substep / np);
    println!("max strain     {:.4} (structural springs, |L|/rest - 1)", summary.max_strain);
    println!("lowest point   {:.4} m (floor at {} m)", summary.lowest_y, scene.floor_y);
    println!(
        "NaN            {}",
        if summary.nan_count == 0 { "none".to_string() } else { format!("{} components", summary.nan_count) }
    );

    if let Some(last) = solver.substep_stats().last() {
        println!(
            "GPU statistics max strain {:.4}, kinetic energy {:.4e} J (last substep, reduced by {})",
            last.max_strain,
            last.kinetic_energy,
            if args.vulkan.stats == StatsArg::Atomics { "atomics" } else { "subgroups" }
        );
    }

    println!("kernel              median us    min us    max us  samples");
    for r in solver.timings().rows {
        println!(
            "  {:<16} {:>10.1} {:>9.1} {:>9.1} {:>8}",
            r.label,
            r.median_ns / 1e3,
            r.min_ns / 1e3,
            r.max_ns / 1e3,
            r.samples
        );
    }

    if let Some((path, format, mut w)) = out {
        match format {
            OutFormat::Obj => write_obj(&mut w, &state, &topo),
            OutFormat::Json => write_json(&mut w, &state),
        }
        .and_then(|_| w.flush())
        .with_context(|| format!("cannot write {}", path.display()))?;
        println!("state written  {}", path.display());
    }
    Ok(if summary.nan_count == 0 { ExitCode::SUCCESS } else { ExitCode::FAILURE })
}

/// The buffer a kernel exists to write (shown when every buffer matches exactly): the
/// first its row writes.
fn primary_output(kernel: KernelRef) -> &'static str {
    match kernel.def.writes.first() {
        Some(Buf::PosOut) | None => "pos",
        Some(b) => b.name(),
    }
}

/// A GPU backend's kernels, runnable one by one.
trait GpuRunner: KernelRunner {
    /// The kernels its recipe dispatches.
    fn recipe_kernels(&self) -> Vec<KernelRef>;
    /// The commands of one substep.
    fn substep_commands(&self) -> Vec<StepCommand>;
}

impl GpuRunner for WgpuSolver {
    fn recipe_kernels(&self) -> Vec<KernelRef> {
        WgpuSolver::recipe_kernels(self)
    }
    fn substep_commands(&self) -> Vec<StepCommand> {
        self.commands().to_vec()
    }
}

impl GpuRunner for VulkanSolver {
    fn recipe_kernels(&self) -> Vec<KernelRef> {
        VulkanSolver::recipe_kernels(self)
    }
    fn substep_commands(&self) -> Vec<StepCommand> {
        self.commands()
    }
}

fn gpu_runner(backend: Backend, n: u32, params: &SimParams) -> Result<Box<dyn GpuRunner>> {
    let scene = Scene::with_n(n);
    Ok(match backend {
        Backend::WgpuNaive => Box::new(WgpuSolver::new(Variant::Naive, scene, params.clone())?),
        Backend::Wgpu => Box::new(WgpuSolver::new(Variant::Optimized, scene, params.clone())?),
        Backend::VulkanNaive => {
            Box::new(VulkanSolver::new(Variant::Naive, scene, params.clone(), vulkan_validation())?)
        }
        Backend::Vulkan => Box::new(VulkanSolver::new(Variant::Optimized, scene, params.clone(), vulkan_validation())?),
        Backend::Cpu | Backend::CpuPar => bail!("{backend:?} is not a GPU backend"),
    })
}

/// One row of `validate`'s table; `width` for the check column.
fn print_check(backend: &str, c: &clothlab_core::validate::Check, width: usize) {
    println!(
        "{backend:<13} {:<width$} {:<7} {:>10.2e} {:>10.2e} {:>10.2e} {:>8.0e}  {}",
        c.what,
        c.buffer,
        c.max_abs,
        c.rms,
        c.error,
        c.bound,
        if c.passed() { "ok" } else { "FAILED" }
    );
}

fn validate(args: ValidateArgs) -> Result<ExitCode> {
    if !(2..=1024).contains(&args.n) {
        bail!("invalid --n {}: must be in 2 ..= 1024", args.n);
    }
    if args.steps == 0 || args.steps > 100_000 {
        bail!("invalid --steps {}: must be in 1 ..= 100000", args.steps);
    }
    let params = SimParams::default();
    let frames = args.steps.div_ceil(params.substeps);
    for &backend in &args.backends {
        if matches!(backend, Backend::Cpu | Backend::CpuPar) {
            bail!("validate checks GPU backends; {backend:?} is the reference itself");
        }
    }
    let mut failed = 0;
    let mut header = false;
    for &backend in &args.backends {
        // The first solver also tells whether there is an adapter at all: print the header
        // only once there is.
        let mut solver = gpu_runner(backend, args.n, &params)?;
        if !std::mem::replace(&mut header, true) {
            println!(
                "{:<13} {:<26} {:<7} {:>10} {:>10} {:>10} {:>8}  result",
                "backend", "check", "buffer", "max abs", "rms", "error", "bound"
            );
        }
        if args.bisect {
            let commands = solver.substep_commands();
            let b = bisect(solver.as_mut(), &commands, &Scene::with_n(args.n), &params, args.steps)?;
            let name = backend.name();
            for split in &b.splits {
                print_check(name, &split.check, 40);
            }
            match &b.culprit {
                Some(k) => {
                    failed += 1;
                    println!(
                        "{name:<13} leaves the bound first after kernel {k} (on the GPU; the CPU engine's twin runs before it)"
                    );
                }
                None => println!("{name:<13} no kernel leaves the bound: every split within it"),
            }
            println!("{:<13} adapter: {}", name, solver.adapter());
            continue;
        }
        let names = solver.recipe_kernels();
        let kernel_checks = validate_kernels(solver.as_mut(), &names, args.n, 0x5eed)?;
        // One row per kernel: its worst buffer relative to the bound.
        let mut rows = Vec::new();
        for &name in &names {
            let shader = name.shader_name();
            let worst = kernel_checks
                .iter()
                .filter(|c| c.what == shader)
                .max_by(|a, b| {
                    let key =
                        |c: &clothlab_core::validate::Check| (c.error / c.bound, c.buffer == primary_output(name));
                    let (ka, kb) = (key(a), key(b));
                    ka.0.total_cmp(&kb.0).then(ka.1.cmp(&kb.1))
                })
                .cloned();
            rows.extend(worst);
        }
        let mut rollout_solver = make_solver(backend, Scene::with_n(args.n), params.clone())?;
        rows.push(validate_rollout(rollout_solver.as_mut(), frames)?);
        let name = rollout_solver.name().to_owned();
        for c in rows {
            failed += usize::from(!c.passed());
            print_check(&name, &c, 26);
        }
        println!("{:<13} adapter: {}", name, solver.adapter());
    }
    println!("kernel errors are relative to the largest value in the buffer; rollout errors are in metres");
    if failed > 0 {
        eprintln!("error: {failed} check(s) over their bound: do not trust this backend's numbers on this adapter");
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}

/// The default view of the scene: the orbit camera's start and a light above and in front.
pub fn default_view(mode: Mode) -> clothlab_core::View {
    clothlab_core::View {
        camera: clothlab_core::OrbitCamera::default(),
        light: [2.0, 5.5, 3.0],
        mode: match mode {
            Mode::Points => clothlab_core::RenderMode::Points,
            Mode::Lines => clothlab_core::RenderMode::Lines,
            Mode::Triangles => clothlab_core::RenderMode::Triangles,
        },
    }
}

fn render(args: RenderArgs) -> Result<ExitCode> {
    let scene = Scene::with_n(args.n);
    scene.validate()?;
    if args.frames > 100_000 {
        bail!("invalid --frames {}: must be in 0 ..= 100000", args.frames);
    }
    if !matches!(args.out.extension().and_then(|e| e.to_str()), Some("png" | "PNG")) {
        bail!("--out {}: the image is written as PNG, use a .png file name", args.out.display());
    }
    let params = SimParams::default();
    let view = default_view(args.mode);
    let is_vulkan = matches!(args.backend, Backend::VulkanNaive | Backend::Vulkan);
    let api = args.api.unwrap_or(if is_vulkan { Api::Vulkan } else { Api::Wgpu });
    if api == Api::Wgpu && is_vulkan || api == Api::Vulkan && matches!(args.backend, Backend::WgpuNaive | Backend::Wgpu)
    {
        bail!(
            "--backend {} draws through its own API: a GPU solver's buffers are drawn without a copy, so pick --api {} (or a CPU backend)",
            args.backend.to_possible_value().map(|v| v.get_name().to_owned()).unwrap_or_default(),
            if is_vulkan { "vulkan" } else { "wgpu" }
        );
    }
    let (pixels, adapter) = match args.backend {
        Backend::Cpu | Backend::CpuPar if api == Api::Vulkan => {
            let exec = if args.backend == Backend::Cpu { Exec::Serial } else { Exec::Parallel };
            let mut solver = CpuSolver::new(exec, scene.clone(), params)?;
            for _ in 0..args.frames {
                solver.step_frame()?;
            }
            let dev = clothlab_vulkan::raw::Device::new(vulkan_validation())?;
            let mut r = VulkanRenderer::new(&dev, &scene, solver.topology(), args.width, args.height)?;
            r.render(&view, VkCloth::Cpu(solver.state_ref()))?;
            (r.read_image()?, format!("{} (Vulkan)", dev.name))
        }
        Backend::Cpu | Backend::CpuPar => {
            let exec = if args.backend == Backend::Cpu { Exec::Serial } else { Exec::Parallel };
            let mut solver = CpuSolver::new(exec, scene.clone(), params)?;
            for _ in 0..args.frames {
                solver.step_frame()?;
            }
            let ctx = clothlab_wgpu::GpuContext::new()?;
            let mut r = WgpuRenderer::new(&ctx, &scene, solver.topology(), args.width, args.height)?;
            r.render(&ctx, &view, ClothSource::Cpu(solver.state_ref()))?;
            (r.read_image(&ctx)?, ctx.describe())
        }
        Backend::VulkanNaive | Backend::Vulkan => {
            let variant = if args.backend == Backend::Vulkan { Variant::Optimized } else { Variant::Naive };
            let options = VulkanOptions { validation: vulkan_validation(), ..Default::default() };
            let mut solver = VulkanSolver::with_options(variant, scene.clone(), params.clone(), options)?;
            for _ in 0..args.frames {
                solver.step_frame()?;
            }
            let (_, topo) = clothlab_core::build(&scene, &params)?;
            let mut r = VulkanRenderer::new(&solver.device(), &scene, &topo, args.width, args.height)?;
            let (pos, normal) = solver.vertex_buffers();
            r.render(&view, VkCloth::Gpu { pos, normal })?;
            (r.read_image()?, format!("{} (Vulkan)", solver.adapter()))
        }
        Backend::WgpuNaive | Backend::Wgpu => {
            let variant = if args.backend == Backend::Wgpu { Variant::Optimized } else { Variant::Naive };
            let mut solver = WgpuSolver::new(variant, scene.clone(), params.clone())?;
            for _ in 0..args.frames {
                solver.step_frame()?;
            }
            let (_, topo) = clothlab_core::build(&scene, &params)?;
            let ctx = solver.context();
            let mut r = WgpuRenderer::new(ctx, &scene, &topo, args.width, args.height)?;
            let (pos, normal) = solver.vertex_buffers();
            r.render(ctx, &view, ClothSource::Gpu { pos, normal })?;
            (r.read_image(ctx)?, solver.adapter())
        }
    };
    image::save_buffer(&args.out, &pixels, args.width, args.height, image::ExtendedColorType::Rgba8)
        .with_context(|| format!("cannot write {}", args.out.display()))?;
    println!(
        "wrote {} ({}x{}, {} frames, {:?}, adapter {adapter})",
        args.out.display(),
        args.width,
        args.height,
        args.frames,
        args.mode
    );
    Ok(ExitCode::SUCCESS)
}

enum OutFormat {
    Obj,
    Json,
}

fn out_format(path: &Path) -> Result<OutFormat> {
    match path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).as_deref() {
        Some("obj") => Ok(OutFormat::Obj),
        Some("json") => Ok(OutFormat::Json),
        _ => bail!("--out {}: unknown format, use a .obj or .json file name", path.display()),
    }
}
