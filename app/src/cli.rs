//! The command line, as clap types and nothing else: what each subcommand takes. The
//! commands themselves are in `commands/` (and `bench/`); the backends, APIs and the one
//! solver factory in the `clothlab` library (`clothlab::backend`).

use std::path::PathBuf;

use clap::{Parser, Subcommand, ValueEnum};
use clothlab::engine::{SolverOptions, StatsMode, VariantSpec};

use clothlab::backend::{Api, Backend, GpuSetup};

#[derive(Parser)]
#[command(name = "clothlab", version, about = "Interactive, GPU-accelerated cloth simulation testbed")]
pub struct Cli {
    /// What to do; without one, the interactive app opens (`run`).
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Which backend wgpu itself runs on (the wgpu backends, the wgpu renderer and wgpu's
    /// overhead benchmarks): `vulkan`, or `gl` (wgpu on OpenGL ES through EGL, beside raw
    /// GL as wgpu-on-Vulkan stands beside raw Vulkan). Default: the adapter wgpu prefers.
    #[arg(long, global = true, value_enum)]
    pub wgpu_backend: Option<WgpuBackend>,
}

/// wgpu's own backends clothlab builds with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum WgpuBackend {
    /// Vulkan.
    Vulkan,
    /// OpenGL (ES 3.1+ with compute) through EGL.
    Gl,
}

#[derive(Subcommand)]
pub enum Command {
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
    Bench(BenchArgs),
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

impl Mode {
    /// The renderer's mode.
    pub fn render_mode(self) -> clothlab::core::RenderMode {
        match self {
            Mode::Points => clothlab::core::RenderMode::Points,
            Mode::Lines => clothlab::core::RenderMode::Lines,
            Mode::Triangles => clothlab::core::RenderMode::Triangles,
        }
    }
}

#[derive(clap::Args)]
pub struct RenderArgs {
    /// Solver backend.
    #[arg(long, value_enum, default_value_t = Backend::Wgpu)]
    pub backend: Backend,
    /// Particles per side of the cloth (default 100, or the scene file's).
    #[arg(long)]
    pub n: Option<u32>,
    /// Frames to simulate before the picture (of `substeps` substeps each).
    #[arg(long, default_value_t = 120)]
    pub frames: u32,
    /// How the cloth is drawn.
    #[arg(long, value_enum, default_value_t = Mode::Triangles)]
    pub mode: Mode,
    /// Image width, pixels.
    #[arg(long, default_value_t = 960)]
    pub width: u32,
    /// Image height, pixels.
    #[arg(long, default_value_t = 640)]
    pub height: u32,
    /// Output PNG file.
    #[arg(long)]
    pub out: PathBuf,
    /// Graphics API of the renderer: wgpu, or raw Vulkan. Default: Vulkan for the Vulkan
    /// solvers (drawn from their buffers), wgpu for the others (CPU solvers upload a frame
    /// to either).
    #[arg(long, value_enum)]
    pub api: Option<Api>,
    /// Worlds, as `sim --envs` (default the scene file's `envs`, else 1; on cpu and
    /// cpu-par); the picture lays them out on a grid (the first 64), or draws `--world`.
    #[arg(long, value_name = "N")]
    pub envs: Option<u32>,
    /// Which world of the batch to draw alone (0-based); without it a batch's worlds are
    /// laid out on a grid.
    #[arg(long, value_name = "K")]
    pub world: Option<usize>,
    #[command(flatten)]
    pub physics: PhysicsArgs,
    #[command(flatten)]
    pub variant: VariantArgs,
}

#[derive(clap::Args)]
pub struct ValidateArgs {
    /// Backends to check (comma-separated): the GPU backends (default every one), or with
    /// `--envs` the batch backends (default cpu,cpu-par).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub backends: Option<Vec<Backend>>,
    /// Particles per side for the kernel checks and the rollout (2 ..= 1024; default 64,
    /// or the scene file's).
    #[arg(long)]
    pub n: Option<u32>,
    /// Substeps of the rollout (rounded up to whole frames).
    #[arg(long, default_value_t = 200)]
    pub steps: u32,
    /// Instead of the checks: a rollout in which every substep runs its first k
    /// dispatches on the CPU engine and the rest on the GPU, for every k, naming the first
    /// kernel after which the GPU leaves the rollout bound (`--steps` substeps of an
    /// `--n` cloth; n = 32 keeps it quick).
    #[arg(long)]
    pub bisect: bool,
    /// Instead of the checks: a batch of N worlds (the lists of `--set` and of the scene
    /// file's `[params]` giving each its values) on each backend, each world against a
    /// single run with its parameters — the same values, or the row fails.
    #[arg(long, value_name = "N")]
    pub envs: Option<u32>,
    /// Check every switch: every flavor of every kernel (constants in storage, uniform
    /// or push constants; colliders in storage or uniform blocks; float or
    /// compare-exchange atomics; the table from storage, an image or uniform constants)
    /// against its twin, and a rollout of every rung of the ladder, the thesis preset and
    /// the other atomics, per GPU API.
    #[arg(long, conflicts_with = "bisect")]
    pub every_switch: bool,
    #[command(flatten)]
    pub physics: PhysicsArgs,
    #[command(flatten)]
    pub variant: VariantArgs,
}

#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// Graphics API of the window.
    #[arg(long, value_enum, default_value_t = Api::Wgpu)]
    pub api: Api,
    /// Solver (default: the optimized GPU solver of the API).
    #[arg(long, value_enum)]
    pub backend: Option<Backend>,
    /// Particles per side of the cloth (10 ..= 1024 in the app; default 64, or the scene
    /// file's).
    #[arg(long)]
    pub n: Option<u32>,
    /// Which world of a batch to show (0-based; default 0): a scene file's `envs` and the
    /// lists of `--set` and of its `[params]` give each world its values.
    #[arg(long, value_name = "K")]
    pub world: Option<usize>,
    /// Quit after this many frames (for tests and screenshots).
    #[arg(long)]
    pub frames: Option<u64>,
    /// Save a PNG of the window (panels included) after `--frames` frames.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Window width, pixels.
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    /// Window height, pixels.
    #[arg(long, default_value_t = 800)]
    pub height: u32,
    /// Test hook: from frame 5 on, grab the cloth under its middle with the cursor tool
    /// and drag it upwards, printing what was grabbed and where it went.
    #[arg(long, hide = true)]
    pub drag_test: bool,
    /// Test hook: halfway through `--frames`, switch to the other graphics API.
    #[arg(long, hide = true)]
    pub switch_api: bool,
    /// Test hook: at frame 3, drop this file on the window (File → Open scene's path),
    /// printing the status bar's message.
    #[arg(long, hide = true, value_name = "FILE")]
    pub drop_file: Option<PathBuf>,
    #[command(flatten)]
    pub physics: PhysicsArgs,
}

impl Default for RunArgs {
    fn default() -> Self {
        Self {
            api: Api::Wgpu,
            backend: None,
            n: None,
            world: None,
            frames: None,
            screenshot: None,
            width: 1280,
            height: 800,
            drag_test: false,
            switch_api: false,
            drop_file: None,
            physics: PhysicsArgs::default(),
        }
    }
}

#[derive(clap::Args)]
pub struct SimArgs {
    /// Solver backend.
    #[arg(long, value_enum, default_value_t = Backend::Cpu)]
    pub backend: Backend,
    /// Particles per side of the cloth (2 ..= 4096; default 100, or the scene file's).
    #[arg(long)]
    pub n: Option<u32>,
    /// Substeps to simulate (rounded up to whole frames of `substeps` each).
    #[arg(long, default_value_t = 1000)]
    pub steps: u64,
    /// Worlds: copies of the scene stepped together, each with its own state and
    /// parameters (`--set damping=[0.01,0.02]` gives one value a world); default the scene
    /// file's `envs`, else 1. On cpu and cpu-par.
    #[arg(long, value_name = "N")]
    pub envs: Option<u32>,
    #[command(flatten)]
    pub physics: PhysicsArgs,
    /// Write the final state: `.obj` (mesh with normals and uvs) or `.json` (full state;
    /// with worlds, every world's, world after world).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Record the run as binary glTF (`.glb`): the cloth with a morph target per recorded
    /// frame and an animation playing them at their times, the colliders as meshes (moving
    /// ones as animated nodes; Blender imports it as shape keys).
    #[arg(long, value_name = "FILE.glb")]
    pub record: Option<PathBuf>,
    /// With `--envs`: the world `--record` records and `--out` writes alone (0-based);
    /// without it every world is recorded (each a node `world k` on a grid) and written.
    #[arg(long, value_name = "K")]
    pub world: Option<usize>,
    /// With `--record`: keep every K-th frame (and the first).
    #[arg(long, value_name = "K", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub record_every: u32,
    /// Count the crossings (edges through triangles they share no vertex with) after every
    /// frame, not only in the final state: the most in a frame and the first frame with any.
    #[arg(long)]
    pub check_crossings: bool,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

/// The simulation parameters every command that simulates takes.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct PhysicsArgs {
    /// How a substep integrates (the help lists `Integrator::ALL`).
    #[arg(long, value_parser = parse_integrator, help = integrator_help())]
    pub integrator: Option<clothlab::core::Integrator>,
    /// Override a simulation parameter, e.g. `--set damping=0.001 --set wind=[2,0,1]`
    /// (names as in `SimParams`; see docs/parameters.md).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
    /// A scene file (the help lists the file's tables: `SceneFile::TABLES`).
    #[arg(long, value_name = "FILE", help = scene_help())]
    pub scene: Option<PathBuf>,
}

impl PhysicsArgs {
    /// The library's form: the scene file (or the default scene), the integrator, the
    /// overrides.
    pub fn physics(&self) -> clothlab::Physics {
        clothlab::Physics {
            scene: match &self.scene {
                Some(path) => clothlab::SceneSource::File(path.clone()),
                None => clothlab::SceneSource::Default,
            },
            integrator: self.integrator,
            set: self.set.clone(),
        }
    }

    /// [`clothlab::Physics::setup`] of [`PhysicsArgs::physics`].
    pub fn setup(&self, n: Option<u32>, default_n: u32) -> anyhow::Result<clothlab::Setup> {
        self.physics().setup(n, default_n)
    }
}

/// `--integrator`'s help, from `Integrator::ALL`.
fn integrator_help() -> String {
    let list: Vec<String> =
        clothlab::core::Integrator::ALL.iter().map(|i| format!("{} ({})", i.name(), i.summary())).collect();
    format!(
        "How a substep integrates: {}. Explicit ones refuse springs they cannot integrate, naming the substeps",
        list.join(", ")
    )
}

/// `--scene`'s help, from `SceneFile::TABLES`.
fn scene_help() -> String {
    format!(
        "A scene file (TOML; see scenes/ and docs/scenes.md) whose keys are {} ([[cloth]] for several cloths). \
         `--n`, `--integrator` and `--set` apply over it",
        clothlab::core::SceneFile::TABLES.join(", ")
    )
}

/// `--integrator`'s value, by its name.
fn parse_integrator(s: &str) -> Result<clothlab::core::Integrator, String> {
    clothlab::core::Integrator::parse(s).ok_or_else(|| {
        let names: Vec<&str> = clothlab::core::Integrator::ALL.iter().map(|i| i.name()).collect();
        format!("unknown integrator `{s}` (known: {})", names.join(", "))
    })
}

/// What `--set-variant` takes (kept in step with `clothlab::engine::variant::SWITCHES` by a
/// test).
pub const SET_VARIANT_HELP: &str = "GPU backends: change one switch of the variant, KEY=VALUE (repeatable). \
The switches (values in ladder order, the naive one first):
  springs=scatter|gather          spring forces per spring with atomics, or per particle
  normals=scatter|gather|frame    vertex normals per triangle with atomics, or per vertex,
                                  every substep; or once per frame, the wind in the
                                  forces gather (needs fusion=clothlab or tile)
  atomics=float|cas               the scatters' atomics: float add, or compare-exchange
  fusion=none|thesis|clothlab|tile
                                  no fusion; the thesis's forces+Verlet+collisions;
                                  clothlab's forces+springs and integrate+collide; or
                                  the whole Verlet substep of a grid in one dispatch
                                  over workgroup-memory tiles (needs 32 KiB of it)
  submit=substep|frame            one queue submission per substep, or per frame
  constants=storage|uniform|push  the step constants: storage, uniform, push constants
  table=storage|image|uniform     the spring table: storage buffers, a sampled image,
                                  or uniform constants with neighbours by offset
  colliders=storage|uniform       spheres and boxes: storage or uniform buffers
  neighbours=load|shuffle         the blocked gathers' neighbour positions: loaded, or
                                  passed between lanes by subgroup shuffles
  draw=copy|shared                the renderer draws from copies made every frame, or
                                  from the simulation's own buffers
  temporal=off|on                 the tiles advance one substep per dispatch, or several
                                  with a deeper halo (a whole frame where the cloth fits
                                  one tile; needs fusion=tile)
  sdf=storage|image               the bodies' distance fields: a storage buffer the
                                  kernel interpolates, or a 3-D image the texture unit
                                  interpolates (within 0.1 cell of the twins)
  specialize=off|on               the kernels as built for every scene, or compiled for
                                  the scene: the code for rods, bodies, Coulomb friction
                                  and moving colliders only where it has them (same bits)
  strain_counts=dispatch|inline|strip
                                  the strain limit's counts of springs over their limit:
                                  a count dispatch before each pass, counted by the pass
                                  itself where it needs them, or by a pass down strips of
                                  rows that computes each spring's length once (same
                                  bits; the optimized preset's on a CPU adapter)
A switch the adapter lacks, or two that exclude each other, is refused in one line.";

/// The variant of the GPU backends: a preset and changes of single switches.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct VariantArgs {
    /// GPU backends: the variant preset, `naive`, `optimized` or `thesis` (the thesis's
    /// optimized CUDA recipe); default: the backend's (`wgpu-naive`: naive, `wgpu`:
    /// optimized). A preset falls back to what the adapter has.
    #[arg(long, value_name = "PRESET")]
    pub variant: Option<String>,
    #[arg(long = "set-variant", value_name = "KEY=VALUE", long_help = SET_VARIANT_HELP)]
    pub set_variant: Vec<String>,
}

impl VariantArgs {
    /// The variant asked for `backend` (`--variant`, else the backend's preset, with the
    /// `--set-variant` changes), or `None` when neither option is given. Refused for a CPU
    /// backend.
    pub fn spec(&self, backend: Backend) -> anyhow::Result<Option<VariantSpec>> {
        clothlab::variant_spec(backend, self.variant.as_deref(), &self.set_variant)
    }
}

/// Options of the GPU backends: the variant and what is computed besides the step.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct GpuArgs {
    /// GPU backends: per-substep statistics (max strain, kinetic energy) on the GPU, by
    /// subgroup reductions (where the API offers them) or by atomics.
    #[arg(long, value_enum, default_value_t = StatsArg::Off)]
    pub stats: StatsArg,
    #[command(flatten)]
    pub variant: VariantArgs,
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

impl GpuArgs {
    /// The GPU solvers' options.
    pub fn options(&self) -> SolverOptions {
        SolverOptions {
            stats: match self.stats {
                StatsArg::Off => StatsMode::Off,
                StatsArg::Atomics => StatsMode::Atomics,
                StatsArg::Subgroups => StatsMode::Subgroups,
            },
        }
    }

    /// The GPU set-up for `backend`: the options and the variant asked for. Refused for
    /// a CPU backend unless left at the defaults.
    pub fn setup(&self, backend: Backend) -> anyhow::Result<GpuSetup> {
        let variant = self.variant.spec(backend)?;
        let setup = GpuSetup { options: self.options(), variant };
        if backend.api().is_none() && setup != GpuSetup::default() {
            anyhow::bail!(
                "--stats, --variant and --set-variant apply to the GPU backends only ({} runs its own SIMD step)",
                backend.name()
            );
        }
        Ok(setup)
    }
}

/// Arguments of `clothlab bench`.
#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// Backends to measure (comma-separated). GPU backends without an adapter are skipped
    /// with a note.
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = [Backend::Cpu, Backend::CpuPar, Backend::WgpuNaive, Backend::Wgpu, Backend::VulkanNaive, Backend::Vulkan, Backend::GlNaive, Backend::Gl])]
    pub backends: Vec<Backend>,
    /// Grid sizes, particles per side (comma-separated, 2 ..= 4096). Sizes a backend would
    /// take longer than `--cell-budget` for are skipped for that backend.
    #[arg(long, value_delimiter = ',', default_values_t = BenchArgs::default_sizes())]
    pub sizes: Vec<u32>,
    /// Substeps measured per kernel at each size (the thesis: 1000 iterations); rounded up
    /// to whole frames. The frame table gets as many frames again.
    #[arg(long, default_value_t = 1000)]
    pub iters: u32,
    /// Output folder (created if missing).
    #[arg(long, default_value = "bench-out")]
    pub out: PathBuf,
    /// Most seconds one backend × size cell may take, predicted from the backend's
    /// previous size; larger cells are skipped and listed in the report.
    #[arg(long, default_value_t = 300.0)]
    pub cell_budget: f64,
    /// Offscreen render target of the frame measurement, pixels (WIDTHxHEIGHT).
    #[arg(long, default_value = "1280x720", value_parser = parse_resolution)]
    pub resolution: (u32, u32),
    /// Rounds of every cell, interleaved (all jobs of a size, then all again, …): each
    /// cell reports the median of its rounds' medians, and the report the spread between
    /// rounds — the machine's run-to-run noise, against which a difference must stand.
    #[arg(long, default_value_t = 1)]
    pub repeat: u32,
    /// Climb the optimisation ladder instead: on each GPU API named in --backends, from
    /// naive to the fastest combination one switch at a time, plus the thesis preset; the
    /// report adds a table and a waterfall plot per API and size.
    #[arg(long)]
    pub ladder: bool,
    /// Measure the integrators instead: work against precision for each (the cost per
    /// simulated second against the error from a reference run) on each backend, at
    /// --sizes (64 and 128 unless given; the backends cpu-par, wgpu and vulkan unless
    /// given). Writes integrators.{md,csv} and a plot per size.
    #[arg(long, conflicts_with = "ladder")]
    pub integrators: bool,
    /// Measure what the grid's regularity buys instead: the scene's n × n cloth as the
    /// grid and loaded as a mesh (the same vertices, triangles and pins), on each backend
    /// at --sizes (64 and 128 unless given; cpu, cpu-par, wgpu, vulkan and gl unless
    /// given), --repeat rounds interleaved; between them the grid without what only a grid
    /// allows (CPU: kernel by kernel; an optimized GPU backend: table=storage,
    /// neighbours=load). A backend that cannot run a cloth is named in the report with its
    /// reason. Writes mesh-vs-grid.{md,csv,svg,png}.
    #[arg(long, conflicts_with_all = ["ladder", "integrators"])]
    pub mesh_vs_grid: bool,
    /// With --mesh-vs-grid: also a mesh of the modelling tools' kind (an OBJ or glTF file,
    /// e.g. the Delaunay disc `scenes/meshes/make_irregular.py --big N FILE` writes), laid
    /// where the grid hangs, unpinned, at every size: give --sizes near the square root
    /// of its vertex count to compare it with the grid of the same count (ns per
    /// particle-substep either way).
    #[arg(long, value_name = "FILE", requires = "mesh_vs_grid")]
    pub irregular: Option<PathBuf>,
    /// Worlds: at each size and each count of worlds, the batch's time per world-substep
    /// against the same worlds run as separate simulations one after another (at most 64
    /// of them, their time per world-substep); the sizes default to 16 and 32, the
    /// backends to cpu and cpu-par. Writes worlds.{md,csv,svg,png}.
    #[arg(long, value_delimiter = ',', value_name = "N,..", conflicts_with_all = ["ladder", "integrators", "mesh_vs_grid"])]
    pub envs: Vec<u32>,
    #[command(flatten)]
    pub physics: PhysicsArgs,
    #[command(flatten)]
    pub variant: VariantArgs,
    /// Skip the API-overhead micro-benchmarks.
    #[arg(long)]
    pub no_overhead: bool,
    /// The GPU memory's peak bandwidth, GB/s: the ladder's report says how far each rung
    /// is from the state's 64 bytes per particle-substep at it, and the plots draw that
    /// bound (default: the data sheet's for a known card, e.g. the H100 80GB HBM3's 3350;
    /// none otherwise). Also with --replot.
    #[arg(long, value_name = "GB/S", value_parser = parse_peak)]
    pub peak_gbps: Option<f64>,
    /// Label of the machine in the report (default: CPU model and core count).
    #[arg(long)]
    pub machine: Option<String>,
    /// Measure nothing: read `--out`/results.json (e.g. copied from another machine) and
    /// write report.md and the plots again.
    #[arg(long)]
    pub replot: bool,
    /// Continue the stopped run whose output folder is DIR: read the cells it finished
    /// (DIR/cells.jsonl), check that the plan is the same (options, machine, adapters,
    /// build; refused in one line if not) and measure only what is missing. Give the
    /// stopped run's options again.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["replot", "integrators", "mesh_vs_grid", "envs"])]
    pub resume: Option<PathBuf>,
}

impl BenchArgs {
    /// `--sizes` when not given.
    pub fn default_sizes() -> Vec<u32> {
        vec![100, 200, 300, 400, 500, 1024, 2048]
    }
}

fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once('x').ok_or_else(|| format!("`{s}`: expected WIDTHxHEIGHT, e.g. 1280x720"))?;
    let w: u32 = w.trim().parse().map_err(|_| format!("`{s}`: width is not a whole number"))?;
    let h: u32 = h.trim().parse().map_err(|_| format!("`{s}`: height is not a whole number"))?;
    if !(16..=8192).contains(&w) || !(16..=8192).contains(&h) {
        return Err(format!("`{s}`: width and height must be in 16 ..= 8192"));
    }
    Ok((w, h))
}

/// `--peak-gbps`: a bandwidth in GB/s, finite and in 1 ..= 100000.
fn parse_peak(s: &str) -> Result<f64, String> {
    let v: f64 = s.trim().parse().map_err(|_| format!("`{s}`: expected a bandwidth in GB/s, e.g. 3350"))?;
    if !(1.0..=1e5).contains(&v) {
        return Err(format!("`{s}`: a memory bandwidth in GB/s must be in 1 ..= 100000"));
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_peak_bandwidth_is_a_number_of_gb_per_second_in_range() {
        assert_eq!(parse_peak("3350"), Ok(3350.0));
        for bad in ["fast", "0", "-5", "NaN", "inf", "1e9"] {
            assert!(parse_peak(bad).unwrap_err().contains(bad), "{bad}");
        }
    }

    #[test]
    fn the_set_variant_help_lists_every_switch_and_value() {
        // The help is a fixed text (clap takes a constant); a switch added to the engine
        // without it here fails this test.
        for s in clothlab::engine::variant::SWITCHES {
            let entry = format!("{}={}", s.key, s.values.join("|"));
            assert!(SET_VARIANT_HELP.contains(&entry), "--set-variant's help lacks `{entry}`");
        }
    }
}
