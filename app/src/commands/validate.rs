//! `clothlab validate`: every GPU kernel against its twin and a rollout against the CPU
//! reference, or (`--bisect`) the split of a rollout between the CPU engine and the GPU.

use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clothlab_core::layout::Buf;
use clothlab_core::validate::Check;
use clothlab_core::validate::validate_rollout;
use clothlab_engine::validate::{
    SPREAD_FACTOR, bisect, every_switch_plan, rollout_bound, rounding_spread, validate_kernels_with,
};
use clothlab_engine::{KernelRef, VariantSpec};

use crate::cli::ValidateArgs;
use crate::out::outln;
use crate::solvers::{Backend, GpuSetup, Shared, make};

/// The buffer a kernel exists to write (shown when every buffer matches exactly): the
/// first its row writes.
fn primary_output(kernel: KernelRef) -> &'static str {
    match kernel.def.writes.first() {
        Some(Buf::PosOut) | None => "pos",
        Some(b) => b.name(),
    }
}

/// One row of `validate`'s table; `width` for the check column.
fn print_check(backend: &str, c: &Check, width: usize) -> Result<(), crate::out::OutputError> {
    outln!(
        "{backend:<13} {:<width$} {:<7} {:>10.2e} {:>10.2e} {:>10.2e} {:>8.0e}  {}",
        c.what,
        c.buffer,
        c.max_abs,
        c.rms,
        c.error,
        c.bound,
        if c.passed() { "ok" } else { "FAILED" }
    )
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

/// Runs `validate`.
pub fn validate(args: ValidateArgs) -> Result<ExitCode> {
    let setup = args.physics.setup(args.n, 64)?;
    let (scene, params) = (setup.scene, setup.params);
    let n = scene.cloth.n;
    if !(2..=1024).contains(&n) {
        bail!("invalid --n {n}: must be in 2 ..= 1024");
    }
    if args.steps == 0 || args.steps > 100_000 {
        bail!("invalid --steps {}: must be in 1 ..= 100000", args.steps);
    }
    let frames = args.steps.div_ceil(params.substeps);
    for &backend in &args.backends {
        if matches!(backend, Backend::Cpu | Backend::CpuPar) {
            bail!("validate checks GPU backends; {backend:?} is the reference itself");
        }
    }
    if args.every_switch && (args.variant.variant.is_some() || !args.variant.set_variant.is_empty()) {
        bail!("--every-switch checks every variant: leave out --variant and --set-variant");
    }
    // --every-switch: one pass per API (the variants, not the backend's preset, vary).
    let mut backends = args.backends.clone();
    if args.every_switch {
        let mut seen = Vec::new();
        backends.retain(|b| {
            let fresh = !seen.contains(&b.api());
            seen.push(b.api());
            fresh
        });
    }
    // What rounding alone does to this scene over the rollout: the rollouts' bound is at
    // least SPREAD_FACTOR times it (a chaotic scene amplifies any last bit).
    let spread = if args.bisect { 0.0 } else { rounding_spread(&scene, &params, frames)? };
    let mut failed = 0;
    let mut header = false;
    let width = if args.bisect {
        40
    } else if args.every_switch {
        48
    } else {
        26
    };
    for backend in backends {
        let setup = GpuSetup { variant: args.variant.spec(backend)?, ..GpuSetup::default() };
        // The first solver also tells whether there is an adapter at all: print the header
        // only once there is.
        let mut any = make(backend, scene.clone(), params.clone(), &setup, &Shared::None)?;
        let commands = any.commands();
        let names = any.recipe_kernels();
        let (caps, api) = any.caps().context("validate checks GPU backends")?;
        let solver = any.runner().context("validate checks GPU backends")?;
        if !std::mem::replace(&mut header, true) {
            outln!(
                "{:<13} {:<width$} {:<7} {:>10} {:>10} {:>10} {:>8}  result",
                "backend",
                "check",
                "buffer",
                "max abs",
                "rms",
                "error",
                "bound"
            )?;
        }
        if args.bisect {
            let b = bisect(solver, &commands, &scene, &params, args.steps)?;
            let name = backend.name();
            for split in &b.splits {
                print_check(name, &split.check, width)?;
            }
            match &b.culprit {
                Some(k) => {
                    failed += 1;
                    outln!(
                        "{name:<13} leaves the bound first after kernel {k} (on the GPU; the CPU engine's twin runs before it)"
                    )?;
                }
                None => outln!("{name:<13} no kernel leaves the bound: every split within it")?,
            }
            outln!("{:<13} adapter: {}", name, solver.adapter())?;
            continue;
        }
        let adapter = solver.adapter();
        let mut rows = Vec::new();
        let mut rollouts: Vec<GpuSetup> = vec![setup.clone()];
        if args.every_switch {
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
        for r in &rollouts {
            let mut rollout_solver = make(backend, scene.clone(), params.clone(), r, &Shared::None)?;
            let mut c = validate_rollout(rollout_solver.get(), frames)?;
            c.bound = rollout_bound(c.bound, rollout_solver.variant().as_ref(), &scene, spread);
            if args.every_switch {
                c.what = format!("rollout {}", rollout_solver.variant().map(|v| v.label()).unwrap_or_default());
            }
            rows.push(c);
        }
        let name = if args.every_switch { api.to_string() } else { any.get_ref().name().to_owned() };
        for c in rows {
            failed += usize::from(!c.passed());
            print_check(&name, &c, width)?;
        }
        outln!("{:<13} adapter: {}", name, adapter)?;
    }
    if header && !args.bisect {
        outln!(
            "rounding alone moves this scene {spread:.2e} m in {} substeps (the CPU solver against its naive recipe and against itself \
             started one ulp off); a rollout's bound is the larger of {:.0e} m per substep and {SPREAD_FACTOR}× that",
            frames * params.substeps,
            clothlab_core::validate::ROLLOUT_BOUND_PER_SUBSTEP
        )?;
    }
    outln!("kernel errors are relative to the largest value in the buffer; rollout errors are in metres")?;
    if failed > 0 {
        eprintln!("error: {failed} check(s) over their bound: do not trust this backend's numbers on this adapter");
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}
