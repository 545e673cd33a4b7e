//! `clothlab validate`: every GPU kernel against its twin and a rollout against the CPU
//! reference, or (`--bisect`) the split of a rollout between the CPU engine and the GPU.

use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clothlab_core::layout::Buf;
use clothlab_core::validate::validate_rollout;
use clothlab_core::{Scene, SimParams};
use clothlab_engine::KernelRef;
use clothlab_engine::validate::{bisect, validate_kernels};

use crate::cli::ValidateArgs;
use crate::solvers::{Backend, make_solver};

/// The buffer a kernel exists to write (shown when every buffer matches exactly): the
/// first its row writes.
fn primary_output(kernel: KernelRef) -> &'static str {
    match kernel.def.writes.first() {
        Some(Buf::PosOut) | None => "pos",
        Some(b) => b.name(),
    }
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

/// Runs `validate`.
pub fn validate(args: ValidateArgs) -> Result<ExitCode> {
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
        let mut any = make_solver(backend, Scene::with_n(args.n), params.clone())?;
        let commands = any.commands();
        let names = any.recipe_kernels();
        let solver = any.runner().context("validate checks GPU backends")?;
        if !std::mem::replace(&mut header, true) {
            println!(
                "{:<13} {:<26} {:<7} {:>10} {:>10} {:>10} {:>8}  result",
                "backend", "check", "buffer", "max abs", "rms", "error", "bound"
            );
        }
        if args.bisect {
            let b = bisect(solver, &commands, &Scene::with_n(args.n), &params, args.steps)?;
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
        let adapter = solver.adapter();
        let kernel_checks = validate_kernels(solver, &names, args.n, 0x5eed)?;
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
        rows.push(validate_rollout(rollout_solver.get(), frames)?);
        let name = rollout_solver.get_ref().name().to_owned();
        for c in rows {
            failed += usize::from(!c.passed());
            print_check(&name, &c, 26);
        }
        println!("{:<13} adapter: {}", name, adapter);
    }
    println!("kernel errors are relative to the largest value in the buffer; rollout errors are in metres");
    if failed > 0 {
        eprintln!("error: {failed} check(s) over their bound: do not trust this backend's numbers on this adapter");
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}
