//! `validate` as data: every GPU kernel against its CPU twin and a rollout against the CPU
//! reference, or (`bisect`) the split of a rollout between the CPU engine and the GPU.
//! Each result comes to a callback as it is known (the command line prints it at once)
//! and all of them back in a [`Validation`].

use anyhow::{Context, Result, bail};
use clothlab_core::layout::Buf;
use clothlab_cpu::validate::{Check, validate_rollout};
use clothlab_engine::validate::{
    SPREAD_FACTOR, bisect, every_switch_plan, rollout_bound, rounding_spread, validate_kernels_with,
};
use clothlab_engine::{KernelRef, VariantSpec};

use crate::backend::{Backend, GpuSetup, Shared, make, variant_spec};

/// What [`validate`] checks.
#[derive(Debug, Clone)]
pub struct ValidateOptions {
    /// The GPU backends (the CPU ones are the reference and are refused).
    pub backends: Vec<Backend>,
    /// The scene and its parameters.
    pub physics: crate::Physics,
    /// Particles per side (2 ..= 1024; default 64, or the scene file's).
    pub n: Option<u32>,
    /// Substeps of the rollout (1 ..= 100000; rounded up to whole frames).
    pub steps: u32,
    /// Instead of the checks: the bisection of a rollout.
    pub bisect: bool,
    /// Every flavor of every kernel and a rollout of every rung, per API.
    pub every_switch: bool,
    /// The variant preset (default: each backend's).
    pub preset: Option<String>,
    /// Single switches over the preset, `KEY=VALUE`.
    pub set_variant: Vec<String>,
    /// Instead of the checks: a batch of this many worlds on each (CPU) backend, each
    /// world against a single run of its parameters ([`validate_worlds`]).
    pub envs: Option<u32>,
}

impl Default for ValidateOptions {
    fn default() -> Self {
        Self {
            backends: Backend::ALL.into_iter().filter(|b| b.is_gpu()).collect(),
            physics: crate::Physics::default(),
            n: None,
            steps: 200,
            bisect: false,
            every_switch: false,
            preset: None,
            set_variant: Vec::new(),
            envs: None,
        }
    }
}

/// One line of a validation.
#[derive(Debug, Clone)]
pub enum Line {
    /// A check: a kernel's worst buffer against its twin, a rollout, or a bisection's split.
    Check {
        /// The backend (with `every_switch`: the API).
        backend: String,
        /// The check.
        check: Check,
    },
    /// A bisection's verdict: the first kernel after which the GPU leaves the bound.
    Culprit {
        /// The backend.
        backend: String,
        /// The kernel, or `None` when every split is within the bound.
        kernel: Option<String>,
    },
    /// The adapter a backend's checks ran on (after its checks).
    Adapter {
        /// The backend (with `every_switch`: the API).
        backend: String,
        /// The adapter.
        adapter: String,
    },
}

/// The outcome of [`validate`].
#[derive(Debug, Clone, Default)]
pub struct Validation {
    /// Every line, in order.
    pub lines: Vec<Line>,
    /// What rounding alone moves the scene over the rollout, m (0 when bisecting).
    pub spread: f32,
    /// Substeps of the rollout.
    pub substeps: u64,
    /// Checks over their bound, and bisections that found a culprit.
    pub failed: usize,
}

impl Validation {
    /// The checks, with their backends.
    pub fn checks(&self) -> impl Iterator<Item = (&str, &Check)> {
        self.lines.iter().filter_map(|l| match l {
            Line::Check { backend, check } => Some((backend.as_str(), check)),
            _ => None,
        })
    }

    /// The adapter of `backend`'s checks.
    pub fn adapter(&self, backend: &str) -> Option<&str> {
        self.lines.iter().find_map(|l| match l {
            Line::Adapter { backend: b, adapter } if b == backend => Some(adapter.as_str()),
            _ => None,
        })
    }

    /// What a rollout's bound is made of, in a sentence.
    pub fn bound_note(&self) -> String {
        format!(
            "rounding alone moves this scene {:.2e} m in {} substeps (the CPU solver against its naive recipe and against itself \
             started one ulp off); a rollout's bound is the larger of {:.0e} m per substep and {SPREAD_FACTOR}× that",
            self.spread,
            self.substeps,
            clothlab_cpu::validate::ROLLOUT_BOUND_PER_SUBSTEP
        )
    }
}

/// The buffer a kernel exists to write (shown when every buffer matches exactly): the
/// first its row writes.
fn primary_output(kernel: KernelRef) -> &'static str {
    match kernel.def.writes.first() {
        Some(Buf::PosOut) | None => "pos",
        Some(b) => b.name(),
    }
}

/// The one row per kernel of `checks`: its worst buffer relative to the bound.
fn worst_rows(kernels: &[KernelRef], checks: &[Check], suffix: &str) -> Vec<Check> {
    let mut rows = Vec::new();
    for &k in kernels {
        let shader = k.report_name();
        let worst = checks
            .iter()
            .filter(|c| c.what == shader)
            .max_by(|a, b| {
                let key = |c: &Check| (c.error / c.bound, c.buffer == primary_output(k));
                let (ka, kb) = (key(a), key(b));
                ka.0.total_cmp(&kb.0).then(ka.1.cmp(&kb.1))
            })
            .cloned();
        rows.extend(worst.map(|mut c| {
            c.what.push_str(suffix);
            c
        }));
    }
    rows
}

/// Runs the checks of `opts`, handing each line to `on_line` as it is known (an error
/// of `on_line` stops the run); all arguments are checked before any backend opens.
pub fn validate(opts: &ValidateOptions, mut on_line: impl FnMut(&Line) -> Result<()>) -> Result<Validation> {
    if let Some(envs) = opts.envs {
        return validate_worlds(opts, envs, on_line);
    }
    let setup = opts.physics.setup(opts.n, 64)?;
    let (scene, params) = (setup.scene, setup.params);
    let n = scene.cloth.n;
    if !(2..=1024).contains(&n) {
        // Named as the user gave it: --n, or the scene file's cloth.
        match (opts.n, &opts.physics.scene) {
            (None, crate::SceneSource::File(path)) => {
                bail!("{}: cloth.n = {n}: validate takes grids of 2 ..= 1024 particles per side", path.display())
            }
            (None, _) => bail!("the scene's cloth.n = {n}: validate takes grids of 2 ..= 1024 particles per side"),
            (Some(_), _) => bail!("invalid --n {n}: must be in 2 ..= 1024"),
        }
    }
    if opts.steps == 0 || opts.steps > 100_000 {
        bail!("invalid --steps {}: must be in 1 ..= 100000", opts.steps);
    }
    if opts.backends.is_empty() {
        bail!("no backend to validate: name at least one GPU backend");
    }
    let frames = opts.steps.div_ceil(params.substeps);
    for &backend in &opts.backends {
        if !backend.is_gpu() {
            bail!("validate checks GPU backends; {} is the reference itself", backend.name());
        }
    }
    if opts.every_switch && (opts.preset.is_some() || !opts.set_variant.is_empty()) {
        bail!("--every-switch checks every variant: leave out --variant and --set-variant");
    }
    if opts.every_switch && opts.bisect {
        bail!("--every-switch and --bisect exclude each other");
    }
    // --every-switch: one pass per API (the variants, not the backend's preset, vary).
    let mut backends = opts.backends.clone();
    if opts.every_switch {
        let mut seen = Vec::new();
        backends.retain(|b| {
            let fresh = !seen.contains(&b.api());
            seen.push(b.api());
            fresh
        });
    }
    let mut out = Validation { substeps: u64::from(frames) * u64::from(params.substeps), ..Validation::default() };
    let mut emit = |out: &mut Validation, line: Line| -> Result<()> {
        match &line {
            Line::Check { check, .. } => out.failed += usize::from(!check.passed()),
            Line::Culprit { kernel, .. } => out.failed += usize::from(kernel.is_some()),
            Line::Adapter { .. } => {}
        }
        on_line(&line)?;
        out.lines.push(line);
        Ok(())
    };
    // What rounding alone does to this scene over the rollout: the rollouts' bound is at
    // least SPREAD_FACTOR times it (a chaotic scene amplifies any last bit).
    out.spread = if opts.bisect { 0.0 } else { rounding_spread(&scene, &params, frames)? };
    for backend in backends {
        let setup = GpuSetup {
            variant: variant_spec(backend, opts.preset.as_deref(), &opts.set_variant)?,
            ..GpuSetup::default()
        };
        let mut any = make(backend, scene.clone(), params.clone(), &setup, &Shared::None)?;
        let commands = any.commands();
        let names = any.recipe_kernels();
        let (caps, api) = any.caps().context("validate checks GPU backends")?;
        let solver = any.runner().context("validate checks GPU backends")?;
        if opts.bisect {
            let b = bisect(solver, &commands, &scene, &params, opts.steps)?;
            let name = backend.name().to_owned();
            for split in &b.splits {
                emit(&mut out, Line::Check { backend: name.clone(), check: split.check.clone() })?;
            }
            emit(&mut out, Line::Culprit { backend: name.clone(), kernel: b.culprit })?;
            emit(&mut out, Line::Adapter { backend: name, adapter: solver.adapter() })?;
            continue;
        }
        let adapter = solver.adapter();
        let mut rows = Vec::new();
        let mut rollouts: Vec<GpuSetup> = vec![setup.clone()];
        if opts.every_switch {
            let plan = every_switch_plan(&caps, api, &scene);
            for set in &plan.kernel_checks {
                let checks = match &set.switches {
                    None => validate_kernels_with(solver, &set.kernels, &scene, 0x5eed, &params)?,
                    Some(switches) => {
                        let spec = VariantSpec::parse("optimized", switches)?;
                        let setup = GpuSetup { variant: Some(spec), ..GpuSetup::default() };
                        let mut other = make(backend, scene.clone(), params.clone(), &setup, &Shared::None)?;
                        let runner = other.runner().context("validate checks GPU backends")?;
                        validate_kernels_with(runner, &set.kernels, &scene, 0x5eed, &params)?
                    }
                };
                rows.extend(worst_rows(&set.kernels, &checks, &set.label));
            }
            rollouts = plan
                .rollouts
                .into_iter()
                .map(|v| GpuSetup { variant: Some(v.into()), ..GpuSetup::default() })
                .collect();
        } else {
            let checks = validate_kernels_with(solver, &names, &scene, 0x5eed, &params)?;
            rows.extend(worst_rows(&names, &checks, ""));
        }
        let name = if opts.every_switch { api.to_string() } else { any.get_ref().name().to_owned() };
        for c in rows {
            emit(&mut out, Line::Check { backend: name.clone(), check: c })?;
        }
        for r in &rollouts {
            let mut rollout_solver = make(backend, scene.clone(), params.clone(), r, &Shared::None)?;
            let mut c = validate_rollout(rollout_solver.get(), frames)?;
            c.bound = rollout_bound(c.bound, rollout_solver.variant().as_ref(), &scene, out.spread);
            if opts.every_switch {
                c.what = format!("rollout {}", rollout_solver.variant().map(|v| v.label()).unwrap_or_default());
            }
            emit(&mut out, Line::Check { backend: name.clone(), check: c })?;
        }
        emit(&mut out, Line::Adapter { backend: name, adapter })?;
    }
    Ok(out)
}

/// `validate --envs N`: on each backend of `opts`, a batch of `envs` worlds run
/// `opts.steps` substeps (whole frames), and each world against a single run of the scene
/// with that world's parameters — on `cpu` for the CPU backends, on the backend itself for
/// a GPU one (its batch runs every world in each dispatch) — a row a world, its positions
/// and its velocities, which must be the same values (bound 0: a world computes a single
/// run's bits). The worlds' values are the lists of `--set` and of the scene file's
/// `[params]`.
pub fn validate_worlds(
    opts: &ValidateOptions,
    envs: u32,
    mut on_line: impl FnMut(&Line) -> Result<()>,
) -> Result<Validation> {
    if opts.bisect || opts.every_switch {
        bail!("--envs checks a batch's worlds against single runs: leave out --bisect and --every-switch");
    }
    if opts.preset.is_some() || !opts.set_variant.is_empty() {
        bail!("--envs checks each backend's own recipe: leave out --variant and --set-variant");
    }
    if opts.steps == 0 || opts.steps > 100_000 {
        bail!("invalid --steps {}: must be in 1 ..= 100000", opts.steps);
    }
    if opts.backends.is_empty() {
        bail!("no backend to validate");
    }
    let batch_opts = |backend| crate::SimOptions {
        backend,
        physics: opts.physics.clone(),
        n: opts.n,
        envs: Some(envs),
        ..Default::default()
    };
    // The lists' lengths checked before anything runs (each world's values when the first
    // batch opens, before it steps).
    let singles: Vec<crate::SimOptions> =
        (0..envs as usize).map(|k| batch_opts(Backend::Cpu).world(k)).collect::<Result<_>>()?;
    let mut out = Validation { lines: Vec::new(), spread: 0.0, substeps: 0, failed: 0 };
    // Each world's single run's end, by the backend it ran on (cpu for both CPU backends).
    let mut reference: Vec<(Backend, Vec<clothlab_core::ClothState>)> = Vec::new();
    for &backend in &opts.backends {
        let mut batch = crate::Sim::open(batch_opts(backend))?;
        let frames = u64::from(opts.steps.div_ceil(batch.params().substeps));
        out.substeps = frames * u64::from(batch.params().substeps);
        batch.step(frames)?;
        let on = if backend.is_gpu() { backend } else { Backend::Cpu };
        if !reference.iter().any(|(b, _)| *b == on) {
            let mut ends = Vec::with_capacity(singles.len());
            for single in &singles {
                let mut one = crate::Sim::open(crate::SimOptions { backend: on, ..single.clone() })?;
                one.step(frames)?;
                ends.push(one.state()?);
            }
            reference.push((on, ends));
        }
        let ends = &reference.iter().find(|(b, _)| *b == on).expect("just made").1;
        let states = batch.world_states()?;
        for (k, (want, got)) in ends.iter().zip(states).enumerate() {
            for (buffer, g, w) in [("pos", &got.pos, &want.pos), ("vel", &got.vel, &want.vel)] {
                let what = format!("world {k} vs its single run");
                let check = clothlab_cpu::validate::compare(&what, buffer, g, w, false, 0.0);
                out.failed += usize::from(!check.passed());
                let line = Line::Check { backend: backend.name().to_string(), check };
                on_line(&line)?;
                out.lines.push(line);
            }
        }
    }
    Ok(out)
}
