//! The one place that turns a backend name into a solver, for the library, the command
//! line and the app: the backends and graphics APIs the user names, and [`AnySolver`], a
//! solver of any backend kept by type so that a GPU solver can hand its buffers to its
//! API's renderer.

use anyhow::{Result, bail};
use clothlab_core::grid::ClothState;
use clothlab_core::{Scene, SimParams, Solver};
use clothlab_cpu::{CpuSolver, Exec};
use clothlab_engine::gpu::Engine as _;
use clothlab_engine::recipe::Command as StepCommand;
use clothlab_engine::validate::KernelRunner;
use clothlab_engine::{Caps, GpuSolver, KernelRef, SolverOptions, Variant, VariantSpec};
use clothlab_gl::{GlCloth, GlContext, GlEngine, GlSolver};
use clothlab_vulkan::{Device, VkCloth, VulkanEngine, VulkanSolver};
use clothlab_wgpu::{ClothSource, GpuContext, WgpuEngine, WgpuSolver};

/// Solver backends.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Backend {
    /// CPU, one thread (the thesis's CPU variant).
    #[default]
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
    /// Raw OpenGL 4.5, the naive recipe (same kernels, naga's GLSL).
    GlNaive,
    /// Raw OpenGL 4.5, the optimized recipe (constants in a uniform or storage block: GL
    /// has no push constants).
    Gl,
}

impl Backend {
    /// Every backend, in the order reports list them.
    pub const ALL: [Backend; 8] = [
        Backend::Cpu,
        Backend::CpuPar,
        Backend::WgpuNaive,
        Backend::Wgpu,
        Backend::VulkanNaive,
        Backend::Vulkan,
        Backend::GlNaive,
        Backend::Gl,
    ];

    /// The backend of a name (`cpu`, `cpu-par`, `wgpu-naive`, `wgpu`, `vulkan-naive`,
    /// `vulkan`, `gl-naive`, `gl`); refused in one line that lists the names.
    pub fn parse(name: &str) -> Result<Backend> {
        match Backend::ALL.into_iter().find(|b| b.name() == name.trim()) {
            Some(b) => Ok(b),
            None => {
                let names: Vec<&str> = Backend::ALL.iter().map(|b| b.name()).collect();
                bail!("unknown backend `{name}` (known: {})", names.join(", "))
            }
        }
    }

    /// Whether it runs on a GPU (through one of the [`Api`]s).
    pub fn is_gpu(self) -> bool {
        self.api().is_some()
    }

    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Backend::Cpu => "cpu",
            Backend::CpuPar => "cpu-par",
            Backend::WgpuNaive => "wgpu-naive",
            Backend::Wgpu => "wgpu",
            Backend::VulkanNaive => "vulkan-naive",
            Backend::Vulkan => "vulkan",
            Backend::GlNaive => "gl-naive",
            Backend::Gl => "gl",
        }
    }

    /// The graphics API of a GPU backend (`None` for the CPU backends).
    pub fn api(self) -> Option<Api> {
        match self {
            Backend::Cpu | Backend::CpuPar => None,
            Backend::WgpuNaive | Backend::Wgpu => Some(Api::Wgpu),
            Backend::VulkanNaive | Backend::Vulkan => Some(Api::Vulkan),
            Backend::GlNaive | Backend::Gl => Some(Api::Gl),
        }
    }

    /// The preset a GPU backend runs unless told otherwise.
    pub fn preset(self) -> Option<&'static str> {
        match self {
            Backend::Wgpu | Backend::Vulkan | Backend::Gl => Some("optimized"),
            Backend::WgpuNaive | Backend::VulkanNaive | Backend::GlNaive => Some("naive"),
            Backend::Cpu | Backend::CpuPar => None,
        }
    }

    /// The variant a GPU backend runs unless told otherwise.
    pub fn variant(self) -> Variant {
        match self {
            Backend::WgpuNaive | Backend::VulkanNaive | Backend::GlNaive => Variant::NAIVE,
            _ => Variant::OPTIMIZED,
        }
    }
}

/// Graphics APIs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Api {
    /// wgpu (Vulkan, Metal, DX12 or GL underneath).
    Wgpu,
    /// Raw Vulkan through ash.
    Vulkan,
    /// Raw OpenGL 4.5 core through glow.
    Gl,
}

impl Api {
    /// Every graphics API.
    pub const ALL: [Api; 3] = [Api::Wgpu, Api::Vulkan, Api::Gl];

    /// The API of a name (`wgpu`, `vulkan`, `gl`); refused in one line that lists them.
    pub fn parse(name: &str) -> Result<Api> {
        match Api::ALL.into_iter().find(|a| a.name() == name.trim()) {
            Some(a) => Ok(a),
            None => bail!("unknown graphics API `{name}` (known: wgpu, vulkan, gl)"),
        }
    }

    /// The name solver names start with and reports use: `wgpu`, `vulkan`, `gl`.
    pub fn name(self) -> &'static str {
        match self {
            Api::Wgpu => "wgpu",
            Api::Vulkan => "vulkan",
            Api::Gl => "gl",
        }
    }

    /// The naive backend of this API (the ladder's base).
    pub fn naive(self) -> Backend {
        match self {
            Api::Wgpu => Backend::WgpuNaive,
            Api::Vulkan => Backend::VulkanNaive,
            Api::Gl => Backend::GlNaive,
        }
    }

    /// The optimized backend of this API.
    pub fn optimized(self) -> Backend {
        match self {
            Api::Wgpu => Backend::Wgpu,
            Api::Vulkan => Backend::Vulkan,
            Api::Gl => Backend::Gl,
        }
    }

    /// The API after this one (the window's API shortcut cycles through them).
    pub fn next(self) -> Api {
        match self {
            Api::Wgpu => Api::Vulkan,
            Api::Vulkan => Api::Gl,
            Api::Gl => Api::Wgpu,
        }
    }
}

/// Which of its backends wgpu opens from now on in this process (the command line's
/// `--wgpu-backend`): GL where `gl`, else Vulkan.
pub fn choose_wgpu_backends(gl: bool) {
    clothlab_wgpu::choose_backends(if gl { wgpu::Backends::GL } else { wgpu::Backends::VULKAN });
}

/// Whether the Vulkan backends run with the Khronos validation layer: in debug builds,
/// or when CLOTHLAB_VALIDATION=1.
pub fn vulkan_validation() -> bool {
    cfg!(debug_assertions) || std::env::var("CLOTHLAB_VALIDATION").as_deref() == Ok("1")
}

/// The device a GPU solver must share with a renderer.
pub enum Shared<'a> {
    /// Draw through wgpu on this context.
    Wgpu(&'a GpuContext),
    /// Draw through raw Vulkan on this device.
    Vulkan(&'a Device),
    /// Draw through raw OpenGL in this context.
    Gl(&'a GlContext),
    /// Every GPU solver opens its own device.
    None,
}

/// How a GPU solver is set up: its options and, where given, its variant (else its
/// backend's preset).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct GpuSetup {
    /// Statistics computed besides the step.
    pub options: SolverOptions,
    /// The variant; `None`: the backend's preset.
    pub variant: Option<VariantSpec>,
}

/// The variant asked for `backend`: `preset` (else the backend's) with the `set_variant`
/// changes (`KEY=VALUE`), or `None` when neither is given. Refused for a CPU backend.
pub fn variant_spec(backend: Backend, preset: Option<&str>, set_variant: &[String]) -> Result<Option<VariantSpec>> {
    if preset.is_none() && set_variant.is_empty() {
        return Ok(None);
    }
    let name = preset.or(backend.preset()).unwrap_or("optimized");
    let spec = VariantSpec::parse(name, set_variant)?;
    if !backend.is_gpu() {
        bail!("--variant and --set-variant apply to the GPU backends only ({} runs its own SIMD step)", backend.name());
    }
    Ok(Some(spec))
}

/// A solver of any backend, kept by type so that a GPU solver on a renderer's device can
/// hand its buffers to the renderer.
pub enum AnySolver {
    /// Serial or rayon.
    Cpu(Box<CpuSolver>),
    /// wgpu; `true` when on the shared context.
    Wgpu(Box<WgpuSolver>, bool),
    /// Raw Vulkan; `true` when on the shared device.
    Vulkan(Box<VulkanSolver>, bool),
    /// Raw OpenGL, in the window's context or a headless one of its own.
    Gl(Box<GlSolver>),
}

/// Makes a solver of `backend`: on `shared`'s device where it is a GPU solver of that
/// API (its buffers drawn with no copy), else on a device of its own. A GPU set-up other
/// than the default is refused for the CPU backends.
pub fn make(
    backend: Backend,
    scene: Scene,
    params: SimParams,
    setup: &GpuSetup,
    shared: &Shared<'_>,
) -> Result<AnySolver> {
    make_worlds(backend, scene, vec![params], setup, shared)
}

/// [`make`] for a batch of worlds, one parameter set each: a GPU solver running them all
/// in each dispatch (`GpuSolver::new_worlds`); a CPU backend takes one (its batches are
/// a solver a world: `Sim`).
pub fn make_worlds(
    backend: Backend,
    scene: Scene,
    worlds: Vec<SimParams>,
    setup: &GpuSetup,
    shared: &Shared<'_>,
) -> Result<AnySolver> {
    if backend.api().is_none() && *setup != GpuSetup::default() {
        bail!("--stats, --variant and --set-variant apply to the GPU backends only");
    }
    let options = setup.options;
    let v = setup.variant.clone().unwrap_or_else(|| backend.variant().into());
    let one = |worlds: Vec<SimParams>| match <[SimParams; 1]>::try_from(worlds) {
        Ok([p]) => Ok(p),
        Err(w) => Err(anyhow::anyhow!("{} worlds: a CPU solver runs one", w.len())),
    };
    Ok(match (backend, shared) {
        (Backend::Cpu, _) => AnySolver::Cpu(Box::new(CpuSolver::new(Exec::Serial, scene, one(worlds)?)?)),
        (Backend::CpuPar, _) => AnySolver::Cpu(Box::new(CpuSolver::new(Exec::Parallel, scene, one(worlds)?)?)),
        (Backend::WgpuNaive | Backend::Wgpu, Shared::Wgpu(ctx)) => {
            let engine = WgpuEngine::on((*ctx).clone());
            AnySolver::Wgpu(Box::new(GpuSolver::new_worlds(engine, v, scene, worlds, options)?), true)
        }
        (Backend::WgpuNaive | Backend::Wgpu, _) => {
            AnySolver::Wgpu(Box::new(GpuSolver::new_worlds(WgpuEngine::new()?, v, scene, worlds, options)?), false)
        }
        (Backend::VulkanNaive | Backend::Vulkan, Shared::Vulkan(dev)) => {
            let engine = VulkanEngine::on_device(dev)?;
            AnySolver::Vulkan(Box::new(GpuSolver::new_worlds(engine, v, scene, worlds, options)?), true)
        }
        (Backend::VulkanNaive | Backend::Vulkan, _) => {
            let engine = VulkanEngine::new(vulkan_validation())?;
            AnySolver::Vulkan(Box::new(GpuSolver::new_worlds(engine, v, scene, worlds, options)?), false)
        }
        (Backend::GlNaive | Backend::Gl, Shared::Gl(ctx)) => {
            AnySolver::Gl(Box::new(GpuSolver::new_worlds(GlEngine::with_context(ctx)?, v, scene, worlds, options)?))
        }
        (Backend::GlNaive | Backend::Gl, _) => {
            AnySolver::Gl(Box::new(GpuSolver::new_worlds(GlEngine::new()?, v, scene, worlds, options)?))
        }
    })
}

impl AnySolver {
    /// The solver.
    pub fn get(&mut self) -> &mut dyn Solver {
        match self {
            AnySolver::Cpu(s) => s.as_mut(),
            AnySolver::Wgpu(s, _) => s.as_mut(),
            AnySolver::Vulkan(s, _) => s.as_mut(),
            AnySolver::Gl(s) => s.as_mut(),
        }
    }

    /// The solver, read only.
    pub fn get_ref(&self) -> &dyn Solver {
        match self {
            AnySolver::Cpu(s) => s.as_ref(),
            AnySolver::Wgpu(s, _) => s.as_ref(),
            AnySolver::Vulkan(s, _) => s.as_ref(),
            AnySolver::Gl(s) => s.as_ref(),
        }
    }

    /// The cloth's connectivity and spring constants, as the solver runs them.
    pub fn topology(&self) -> &clothlab_core::ClothTopology {
        match self {
            AnySolver::Cpu(s) => s.topology(),
            AnySolver::Wgpu(s, _) => s.topology(),
            AnySolver::Vulkan(s, _) => s.topology(),
            AnySolver::Gl(s) => s.topology(),
        }
    }

    /// A GPU solver's worlds (`None` for the CPU solvers, whose batches are a solver a
    /// world).
    pub fn batch(&mut self) -> Option<&mut dyn clothlab_engine::Batch> {
        match self {
            AnySolver::Cpu(_) => None,
            AnySolver::Wgpu(s, _) => Some(s.as_mut()),
            AnySolver::Vulkan(s, _) => Some(s.as_mut()),
            AnySolver::Gl(s) => Some(s.as_mut()),
        }
    }

    /// [`AnySolver::batch`], to read.
    pub fn batch_ref(&self) -> Option<&dyn clothlab_engine::Batch> {
        match self {
            AnySolver::Cpu(_) => None,
            AnySolver::Wgpu(s, _) => Some(s.as_ref()),
            AnySolver::Vulkan(s, _) => Some(s.as_ref()),
            AnySolver::Gl(s) => Some(s.as_ref()),
        }
    }

    /// A GPU solver's kernels, runnable one by one (`None` for the CPU solvers).
    pub fn runner(&mut self) -> Option<&mut dyn KernelRunner> {
        match self {
            AnySolver::Cpu(_) => None,
            AnySolver::Wgpu(s, _) => Some(s.as_mut()),
            AnySolver::Vulkan(s, _) => Some(s.as_mut()),
            AnySolver::Gl(s) => Some(s.as_mut()),
        }
    }

    /// The commands of one substep of a GPU solver (empty for the CPU solvers).
    pub fn commands(&self) -> Vec<StepCommand> {
        match self {
            AnySolver::Cpu(_) => Vec::new(),
            AnySolver::Wgpu(s, _) => s.commands(),
            AnySolver::Vulkan(s, _) => s.commands(),
            AnySolver::Gl(s) => s.commands(),
        }
    }

    /// The kernels one substep of a GPU solver dispatches.
    pub fn recipe_kernels(&self) -> Vec<KernelRef> {
        match self {
            AnySolver::Cpu(_) => Vec::new(),
            AnySolver::Wgpu(s, _) => s.recipe_kernels(),
            AnySolver::Vulkan(s, _) => s.recipe_kernels(),
            AnySolver::Gl(s) => s.recipe_kernels(),
        }
    }

    /// What the adapter of a GPU solver offers that variants use, and its API's name.
    pub fn caps(&self) -> Option<(Caps, &'static str)> {
        match self {
            AnySolver::Cpu(_) => None,
            AnySolver::Wgpu(s, _) => Some((s.caps(), s.engine().info().api)),
            AnySolver::Vulkan(s, _) => Some((s.caps(), s.engine().info().api)),
            AnySolver::Gl(s) => Some((s.caps(), s.engine().info().api)),
        }
    }

    /// The variant a GPU solver runs.
    pub fn variant(&self) -> Option<Variant> {
        match self {
            AnySolver::Cpu(_) => None,
            AnySolver::Wgpu(s, _) => Some(s.variant()),
            AnySolver::Vulkan(s, _) => Some(s.variant()),
            AnySolver::Gl(s) => Some(s.variant()),
        }
    }

    /// Where it runs: the adapter (and API), or the CPU.
    pub fn adapter(&self) -> String {
        match self {
            AnySolver::Cpu(_) => "CPU".into(),
            AnySolver::Wgpu(s, _) => s.adapter(),
            AnySolver::Vulkan(s, _) => format!("{} (Vulkan)", s.adapter()),
            AnySolver::Gl(s) => s.adapter(),
        }
    }

    /// Waits until the solver's last frame is done on the GPU.
    pub fn finish(&mut self) -> Result<()> {
        match self {
            AnySolver::Cpu(_) => Ok(()),
            AnySolver::Wgpu(s, _) => Ok(s.engine().context().wait_idle()?),
            AnySolver::Vulkan(s, _) => Ok(s.engine().device().wait_idle()?),
            AnySolver::Gl(s) => Ok(s.finish()?),
        }
    }
}

/// The cloth as the wgpu renderer takes it: the solver's buffers when it is a wgpu solver
/// on the shared context, else a state (`copy` holds a read-back one).
pub fn wgpu_cloth<'a>(solver: &'a mut AnySolver, copy: &'a mut Option<ClothState>) -> Result<ClothSource<'a>> {
    Ok(match solver {
        AnySolver::Wgpu(s, true) => {
            let (pos, normal) = s.vertex_buffers();
            ClothSource::Gpu { pos, normal }
        }
        AnySolver::Cpu(s) => ClothSource::Cpu(s.state_ref()),
        other => ClothSource::Cpu(copy.insert(other.get().state()?)),
    })
}

/// The cloth as the GL renderer in `ctx` takes it (see [`wgpu_cloth`]).
pub fn gl_cloth<'a>(
    solver: &'a mut AnySolver,
    copy: &'a mut Option<ClothState>,
    ctx: &GlContext,
) -> Result<GlCloth<'a>> {
    Ok(match solver {
        AnySolver::Gl(s) if s.engine().context().same(ctx) => {
            let (&pos, &normal) = s.vertex_buffers();
            GlCloth::Gpu { pos, normal }
        }
        AnySolver::Cpu(s) => GlCloth::Cpu(s.state_ref()),
        other => GlCloth::Cpu(copy.insert(other.get().state()?)),
    })
}

/// The cloth as the Vulkan renderer takes it (see [`wgpu_cloth`]).
pub fn vulkan_cloth<'a>(solver: &'a mut AnySolver, copy: &'a mut Option<ClothState>) -> Result<VkCloth<'a>> {
    Ok(match solver {
        AnySolver::Vulkan(s, true) => {
            let (pos, normal) = s.vertex_buffers();
            VkCloth::Gpu { pos, normal }
        }
        AnySolver::Cpu(s) => VkCloth::Cpu(s.state_ref()),
        other => VkCloth::Cpu(copy.insert(other.get().state()?)),
    })
}
