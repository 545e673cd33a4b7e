//! `clothlab validate`: every GPU kernel against its twin and a rollout against the CPU
//! reference, or (`--bisect`) the split of a rollout between the CPU engine and the GPU —
//! `clothlab::validate`, printed as a table while it runs.

use std::process::ExitCode;

use anyhow::Result;
use clothlab::Backend;
use clothlab::cpu::validate::Check;
use clothlab::validate::{Line, ValidateOptions, validate as run};

use crate::cli::ValidateArgs;
use crate::out::outln;

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

/// Runs `validate`.
pub fn validate(args: ValidateArgs) -> Result<ExitCode> {
    let backends = args.backends.clone().unwrap_or_else(|| match args.envs {
        Some(_) => vec![Backend::Cpu, Backend::CpuPar],
        None => Backend::ALL.into_iter().filter(|b| b.is_gpu()).collect(),
    });
    let opts = ValidateOptions {
        backends,
        physics: args.physics.physics(),
        n: args.n,
        steps: args.steps,
        bisect: args.bisect,
        every_switch: args.every_switch,
        preset: args.variant.variant.clone(),
        set_variant: args.variant.set_variant.clone(),
        envs: args.envs,
    };
    let width = if args.bisect {
        40
    } else if args.every_switch {
        48
    } else {
        26
    };
    // The header once the first backend has given a line (there is an adapter at all).
    let mut header = false;
    let result = run(&opts, |line| {
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
        match line {
            Line::Check { backend, check } => print_check(backend, check, width)?,
            Line::Culprit { backend, kernel: Some(k) } => outln!(
                "{backend:<13} leaves the bound first after kernel {k} (on the GPU; the CPU engine's twin runs before it)"
            )?,
            Line::Culprit { backend, kernel: None } => {
                outln!("{backend:<13} no kernel leaves the bound: every split within it")?
            }
            Line::Adapter { backend, adapter } => outln!("{backend:<13} adapter: {adapter}")?,
        }
        Ok(())
    })?;
    if args.envs.is_some() {
        outln!(
            "a world's error is its largest difference from its single run, in metres (m/s for vel): a world computes a single run's values"
        )?;
    } else {
        if header && !args.bisect {
            outln!("{}", result.bound_note())?;
        }
        outln!("kernel errors are relative to the largest value in the buffer; rollout errors are in metres")?;
    }
    if result.failed > 0 {
        eprintln!(
            "error: {} check(s) over their bound: do not trust this backend's numbers on this adapter",
            result.failed
        );
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}
