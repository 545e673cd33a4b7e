//! `clothlab bench --integrators`: work against precision for every integrator.
//!
//! The problem is the cloth of the default scene hanging from its two pinned corners with
//! no colliders, no strain limit and no wind, in physical units (the same fabric at every
//! n), released from rest for [`SIM_SECONDS`]. Each integrator runs it at a ladder of
//! substeps per frame — the explicit ones from the fewest they are stable with, implicit
//! and XPBD from one — on each backend, and its final positions are compared with a
//! reference: RK4 on the CPU at four times the substeps RK4 needs. The cost is the wall
//! time per substep (the GPU waited for), and per simulated second; the error is the RMS
//! (and max) distance of the particles from the reference.

use std::fmt::Write as _;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Result;
use clothlab::core::params::MAX_SUBSTEPS;
use clothlab::core::{Integrator, Scene, SimParams, Solver, StiffnessUnits};
use clothlab::cpu::{CpuSolver, Exec};
use plotters::coord::Shift;
use plotters::prelude::*;

use super::plot::{FONT, Figure, both, err};
use super::{Request, all_backends, cpu_label, make_out_dir};
use crate::cli::BenchArgs;
use crate::out::outln;
use clothlab::backend::{Backend, GpuSetup, Shared, make};

/// Simulated time of every run, s (six frames of 1/60 s).
pub const SIM_SECONDS: f32 = 0.1;
/// The accuracy the summary compares costs at: RMS error from the reference, m.
pub const TARGET_ERROR: f64 = 1e-3;

/// One run: an integrator at one substep count on one backend.
#[derive(Debug, Clone)]
pub struct Run {
    /// Integrator name.
    pub integrator: &'static str,
    /// Backend name.
    pub backend: String,
    /// Particles per side.
    pub n: u32,
    /// Substeps per frame.
    pub substeps: u32,
    /// Substep, s.
    pub dt: f64,
    /// Median wall time per substep, ns.
    pub ns_per_substep: f64,
    /// Compute seconds per simulated second.
    pub cost: f64,
    /// RMS distance from the reference, m.
    pub rms: f64,
    /// Largest distance from the reference, m.
    pub max: f64,
}

/// The parameters of the problem for `integrator` at `substeps` per frame.
fn problem(base: &SimParams, integrator: Integrator, substeps: u32) -> SimParams {
    SimParams {
        integrator,
        substeps,
        stiffness_units: StiffnessUnits::Physical,
        strain_iterations: 0,
        wind: [0.0; 3],
        damping: 0.0,
        ..base.clone()
    }
}

/// The fewest substeps per frame `integrator` is stable with on `scene` (None: more than
/// the most a frame may have).
fn fewest(base: &SimParams, integrator: Integrator, scene: &Scene) -> Option<u32> {
    let spacing = scene.cloth.size / (scene.cloth.n - 1) as f32;
    let ok = |s: u32| problem(base, integrator, s).validate_for(scene.cloth.n, spacing).is_ok();
    // Stable from some count up.
    let most = MAX_SUBSTEPS;
    if !ok(most) {
        return None;
    }
    let (mut lo, mut hi) = (0, most);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if ok(mid) { hi = mid } else { lo = mid }
    }
    Some(hi)
}

fn frames() -> u32 {
    (SIM_SECONDS * 60.0).round() as u32
}

/// Runs `solver` for the problem's frames; the median frame time and the positions.
fn simulate(solver: &mut dyn Solver) -> Result<(f64, Vec<[f32; 4]>)> {
    solver.set_kernel_timing(false);
    let mut times = Vec::new();
    for _ in 0..frames() {
        let t = Instant::now();
        solver.step_frame()?;
        times.push(t.elapsed().as_nanos() as f64);
    }
    let pos = solver.state()?.pos;
    times.sort_by(f64::total_cmp);
    Ok((times[times.len() / 2], pos))
}

/// RMS and max distance of `a` from `b`, m.
fn distance(a: &[[f32; 4]], b: &[[f32; 4]]) -> (f64, f64) {
    let d: Vec<f64> =
        a.iter().zip(b).map(|(x, y)| (0..3).map(|k| (x[k] as f64 - y[k] as f64).powi(2)).sum::<f64>().sqrt()).collect();
    let rms = (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt();
    (rms, d.iter().copied().fold(0.0, f64::max))
}

/// Measures every integrator on `backends` at `sizes`; returns the runs and the notes
/// (what was skipped and why).
pub fn measure(
    base: &SimParams,
    backends: &[Backend],
    sizes: &[u32],
    budget_s: f64,
) -> Result<(Vec<Run>, Vec<String>)> {
    let mut runs = Vec::new();
    let mut notes = Vec::new();
    let mut references = Vec::new();
    for &n in sizes {
        let mut scene = Scene::with_n(n);
        scene.spheres.clear();
        scene.boxes.clear();
        // RK4 at four times the substeps it needs (its truncation error 256 times smaller
        // than at its limit; the state in (x, v) keeps the motion at any count up to
        // MAX_SUBSTEPS), or where RK4 cannot run at all, implicit Euler with 64 CG
        // iterations at the most substeps a frame may have.
        let most = MAX_SUBSTEPS;
        let (ref_integrator, ref_substeps) = match fewest(base, Integrator::Rk4, &scene) {
            Some(r) => (Integrator::Rk4, (4 * r).min(most)),
            None => (Integrator::Implicit, most),
        };
        eprintln!("n = {n}: reference {} at {ref_substeps} substeps per frame on cpu-par", ref_integrator.name());
        let ref_params = SimParams { cg_iterations: 64, ..problem(base, ref_integrator, ref_substeps) };
        let mut reference = CpuSolver::new(Exec::Parallel, scene.clone(), ref_params)?;
        let (_, want) = simulate(&mut reference)?;
        references.push(format!("n = {n}: {} at {ref_substeps} substeps per frame", ref_integrator.name()));
        for integrator in Integrator::ALL {
            let ladder: Vec<u32> = match fewest(base, integrator, &scene) {
                None => {
                    let spacing = scene.cloth.size / (n - 1) as f32;
                    let why = problem(base, integrator, MAX_SUBSTEPS).validate_for(n, spacing).err().map(|e| e.reason);
                    notes.push(format!(
                        "n = {n}: {} at no substep count: {}",
                        integrator.name(),
                        why.unwrap_or_default()
                    ));
                    continue;
                }
                Some(s) if integrator.explicit() => vec![s, 2 * s, 4 * s, 8 * s],
                Some(_) => vec![1, 2, 4, 8, 16, 32, 64, 128, 256],
            };
            // Every rung up to 256 substeps: the reference (fourth order at four times
            // its need) is far closer to the exact motion than any first- or
            // second-order rung (RK4 at 2× its need is within 2e-7 m of it at n = 128,
            // implicit Euler at 256 substeps about 3e-5 m). Only the reference's own
            // integrator stops below it, where it would be compared with itself.
            let ladder: Vec<u32> = ladder
                .into_iter()
                .filter(|&s| s <= MAX_SUBSTEPS && (integrator != ref_integrator || s < ref_substeps))
                .collect();
            for &backend in backends {
                // The cost per particle-substep of this backend's last run predicts the next.
                let mut per_particle_substep: Option<f64> = None;
                for &s in &ladder {
                    let total = (frames() * s) as f64 * (n * n) as f64;
                    if let Some(c) = per_particle_substep
                        && c * total / 1e9 > budget_s
                    {
                        notes.push(format!(
                            "n = {n}: {} on {} at {s} substeps per frame: predicted {:.0} s, over --cell-budget",
                            integrator.name(),
                            backend.name(),
                            c * total / 1e9
                        ));
                        break;
                    }
                    let p = problem(base, integrator, s);
                    let mut any = make(backend, scene.clone(), p.clone(), &GpuSetup::default(), &Shared::None)?;
                    let (frame_ns, got) = simulate(any.get())?;
                    let (rms, max) = distance(&got, &want);
                    let ns = frame_ns / s as f64;
                    per_particle_substep = Some(ns / (n * n) as f64);
                    let dt = p.dt() as f64;
                    let run = Run {
                        integrator: integrator.name(),
                        backend: backend.name().into(),
                        n,
                        substeps: s,
                        dt,
                        ns_per_substep: ns,
                        cost: ns / 1e9 / dt,
                        rms,
                        max,
                    };
                    eprintln!(
                        "n = {n} {:17} {:8} {s:4} substeps: {:9.3} ms/substep, {:8.2} s per simulated s, RMS error {:.2e} m",
                        run.integrator,
                        run.backend,
                        ns / 1e6,
                        run.cost,
                        rms
                    );
                    runs.push(run);
                }
            }
        }
    }
    notes.splice(0..0, references.into_iter().map(|r| format!("reference: {r}")));
    Ok((runs, notes))
}

/// The CSV of the runs.
pub fn csv(runs: &[Run]) -> String {
    let mut s = String::from(
        "integrator,backend,n,substeps_per_frame,dt_s,ns_per_substep,cost_s_per_sim_s,rms_error_m,max_error_m\n",
    );
    for r in runs {
        let _ = writeln!(
            s,
            "{},{},{},{},{:e},{:.1},{:.4},{:e},{:e}",
            r.integrator, r.backend, r.n, r.substeps, r.dt, r.ns_per_substep, r.cost, r.rms, r.max
        );
    }
    s
}

/// The runs of an integrators.csv that [`csv`] wrote (for `--replot`).
pub fn read_csv(text: &str) -> Result<Vec<Run>> {
    let mut runs = Vec::new();
    for (i, line) in text.lines().enumerate().skip(1).filter(|(_, l)| !l.trim().is_empty()) {
        let f: Vec<&str> = line.split(',').collect();
        let bad = || anyhow::anyhow!("integrators.csv line {}: not a row clothlab wrote", i + 1);
        if f.len() != 9 {
            return Err(bad());
        }
        let integrator = Integrator::ALL.iter().map(|x| x.name()).find(|x| *x == f[0]).ok_or_else(bad)?;
        let num = |k: usize| f[k].parse::<f64>().map_err(|_| bad());
        runs.push(Run {
            integrator,
            backend: f[1].to_owned(),
            n: f[2].parse().map_err(|_| bad())?,
            substeps: f[3].parse().map_err(|_| bad())?,
            dt: num(4)?,
            ns_per_substep: num(5)?,
            cost: num(6)?,
            rms: num(7)?,
            max: num(8)?,
        });
    }
    Ok(runs)
}

/// Draws the plots of `out`/integrators.csv again (`bench --integrators --replot`); the
/// machine's label is read from integrators.md beside it.
pub fn replot(out: &std::path::Path) -> Result<Vec<std::path::PathBuf>> {
    use anyhow::Context as _;
    let path = out.join("integrators.csv");
    let text = std::fs::read_to_string(&path).with_context(|| format!("cannot read {}", path.display()))?;
    let runs = read_csv(&text)?;
    let md = std::fs::read_to_string(out.join("integrators.md")).unwrap_or_default();
    let machine = md.lines().find_map(|l| l.strip_prefix("Machine: ")).unwrap_or("unknown machine").to_owned();
    let mut sizes: Vec<u32> = runs.iter().map(|r| r.n).collect();
    sizes.dedup();
    let mut files = Vec::new();
    for n in sizes {
        let (svg, png) = both(&WorkPrecision { runs: &runs, n, machine: &machine })?;
        for (name, bytes) in
            [(format!("integrators-n{n}.svg"), svg.into_bytes()), (format!("integrators-n{n}.png"), png)]
        {
            let p = out.join(name);
            clothlab::files::write_bytes(&p, &bytes)?;
            files.push(p);
        }
    }
    Ok(files)
}

/// The report section: every run, then the cost at equal accuracy.
pub fn report(runs: &[Run], notes: &[String], machine: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# clothlab bench --integrators\n\nMachine: {machine}\n");
    let _ = writeln!(
        s,
        "The default cloth hanging from its two corners, no colliders, no strain limit, no wind, physical stiffness (the same fabric at every n), {SIM_SECONDS} s from rest; the error is the RMS distance of the particles from a reference run on the CPU (below: RK4 at four times the substeps it needs, or implicit Euler with 64 CG iterations at 1024 substeps where RK4 cannot run). Cost: wall time per substep (GPU waited for), and compute seconds per simulated second.\n"
    );
    let mut sizes: Vec<u32> = runs.iter().map(|r| r.n).collect();
    sizes.dedup();
    for n in sizes {
        let _ = writeln!(s, "## n = {n}\n");
        let _ = writeln!(
            s,
            "| integrator | backend | substeps/frame | ms/substep | s per simulated s | RMS error m | max error m |"
        );
        let _ = writeln!(s, "|---|---|---:|---:|---:|---:|---:|");
        for r in runs.iter().filter(|r| r.n == n) {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {:.3} | {:.2} | {:.2e} | {:.2e} |",
                r.integrator,
                r.backend,
                r.substeps,
                r.ns_per_substep / 1e6,
                r.cost,
                r.rms,
                r.max
            );
        }
        let _ = writeln!(s, "\nAt equal accuracy (RMS error ≤ {TARGET_ERROR:e} m): the cheapest run of each\n");
        let _ = writeln!(s, "| integrator | backend | substeps/frame | s per simulated s |");
        let _ = writeln!(s, "|---|---|---:|---:|");
        let mut keys: Vec<(&str, &str)> =
            runs.iter().filter(|r| r.n == n).map(|r| (r.integrator, r.backend.as_str())).collect();
        keys.dedup();
        for (i, b) in keys {
            let best = runs
                .iter()
                .filter(|r| r.n == n && r.integrator == i && r.backend == b && r.rms <= TARGET_ERROR)
                .min_by(|x, y| x.cost.total_cmp(&y.cost));
            match best {
                Some(r) => {
                    let _ = writeln!(s, "| {i} | {b} | {} | {:.2} |", r.substeps, r.cost);
                }
                None => {
                    let _ = writeln!(s, "| {i} | {b} | — | not reached |");
                }
            }
        }
        let _ = writeln!(s, "\n![work–precision at n = {n}](integrators-n{n}.svg)\n");
    }
    if !notes.is_empty() {
        let _ = writeln!(s, "## References, and what was not run\n");
        for note in notes {
            let _ = writeln!(s, "- {note}");
        }
    }
    s
}

/// The work–precision plot of one size: RMS error against cost per simulated second,
/// log–log, a line per integrator and backend.
pub struct WorkPrecision<'a> {
    /// Every run.
    pub runs: &'a [Run],
    /// The size plotted.
    pub n: u32,
    /// The machine, for the title.
    pub machine: &'a str,
}

fn integrator_colour(name: &str) -> RGBColor {
    match name {
        "verlet" => RGBColor(20, 90, 200),
        "euler" => RGBColor(150, 150, 150),
        "symplectic-euler" => RGBColor(120, 170, 230),
        "rk2" => RGBColor(240, 150, 110),
        "rk4" => RGBColor(200, 40, 30),
        "implicit" => RGBColor(30, 150, 60),
        _ => RGBColor(150, 60, 170),
    }
}

impl Figure for WorkPrecision<'_> {
    fn size(&self) -> (u32, u32) {
        (1000, 680)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(err)?;
        let runs: Vec<&Run> = self.runs.iter().filter(|r| r.n == self.n && r.rms > 0.0).collect();
        if runs.is_empty() {
            return Ok(());
        }
        let (x0, x1) = runs.iter().fold((f64::MAX, 0.0f64), |(a, b), r| (a.min(r.cost), b.max(r.cost)));
        let (y0, y1) = runs.iter().fold((f64::MAX, 0.0f64), |(a, b), r| (a.min(r.rms), b.max(r.rms)));
        let n = self.n;
        let mut chart = ChartBuilder::on(root)
            .caption(
                format!("Work against precision at {n}×{n} — {} (circles: CPU, triangles: GPU)", self.machine),
                (FONT, 20),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            // Room on the right for the legend, clear of the costliest runs.
            .build_cartesian_2d((x0 / 1.5..x1 * 12.0).log_scale(), (y0 / 2.0..y1 * 2.0).log_scale())
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("compute seconds per simulated second (log)")
            .y_desc("RMS error from the reference, m (log)")
            .x_label_formatter(&|v| format!("{v}"))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .label_style((FONT, 13))
            .draw()
            .map_err(err)?;
        let mut keys: Vec<(&str, &str)> = runs.iter().map(|r| (r.integrator, r.backend.as_str())).collect();
        keys.sort();
        keys.dedup();
        let mut labelled: Vec<&str> = Vec::new();
        for (i, b) in keys {
            let pts: Vec<(f64, f64)> =
                runs.iter().filter(|r| r.integrator == i && r.backend == b).map(|r| (r.cost, r.rms)).collect();
            let c = integrator_colour(i);
            let series = chart.draw_series(LineSeries::new(pts.clone(), c.stroke_width(2))).map_err(err)?;
            // One legend entry per integrator: the marker tells the backend.
            if !labelled.contains(&i) {
                labelled.push(i);
                series.label(i).legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
            }
            match b {
                "cpu" | "cpu-par" => chart.draw_series(pts.iter().map(|p| Circle::new(*p, 4, c.filled()))).map(|_| ()),
                _ => chart.draw_series(pts.iter().map(|p| TriangleMarker::new(*p, 5, c.filled()))).map(|_| ()),
            }
            .map_err(err)?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font((FONT, 12))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(err)?;
        Ok(())
    }
}

/// Writes `integrators.csv`, `integrators.md` and the plots into `out`.
pub fn write(out: &std::path::Path, runs: &[Run], notes: &[String], machine: &str) -> Result<()> {
    clothlab::files::write_bytes(&out.join("integrators.csv"), csv(runs).as_bytes())?;
    clothlab::files::write_bytes(&out.join("integrators.md"), report(runs, notes, machine).as_bytes())?;
    let mut sizes: Vec<u32> = runs.iter().map(|r| r.n).collect();
    sizes.dedup();
    for n in sizes {
        let (svg, png) = both(&WorkPrecision { runs, n, machine })?;
        clothlab::files::write_bytes(&out.join(format!("integrators-n{n}.svg")), svg.as_bytes())?;
        clothlab::files::write_bytes(&out.join(format!("integrators-n{n}.png")), &png)?;
    }
    Ok(())
}

/// `bench --integrators`: [`measure`], [`write()`] and [`report`] with the mode's own
/// defaults: the size list (for the kernel tables) 64 and 128 where left at the default,
/// and the backends, if left at all of them, the fast three.
pub fn run(args: &BenchArgs, request: &Request) -> Result<ExitCode> {
    let (params, backends, sizes) = (&request.params, &request.backends[..], &request.sizes[..]);
    let defaults = BenchArgs::default_sizes();
    let sizes: Vec<u32> = if sizes == defaults.as_slice() { vec![64, 128] } else { sizes.to_vec() };
    let backends: Vec<Backend> =
        if all_backends(backends) { vec![Backend::CpuPar, Backend::Wgpu, Backend::Vulkan] } else { backends.to_vec() };
    make_out_dir(&args.out)?;
    let (runs, notes) = measure(params, &backends, &sizes, args.cell_budget)?;
    let machine = args.machine.clone().unwrap_or_else(cpu_label);
    write(&args.out, &runs, &notes, &machine)?;
    outln!("{}", report(&runs, &notes, &machine))?;
    outln!("wrote {}/integrators.{{md,csv}} and the plots", args.out.display())?;
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_csv_reads_back_what_it_wrote_and_refuses_other_rows() {
        let run = |integrator, substeps, rms: f64| Run {
            integrator,
            backend: "cpu-par".into(),
            n: 64,
            substeps,
            dt: 1.0 / 60.0 / substeps as f64,
            ns_per_substep: 1234.5,
            cost: 0.5,
            rms,
            max: 2.0 * rms,
        };
        let runs = vec![run("xpbd", 16, 6.79e-4), run("rk4", 20, 9.57e-7)];
        let back = read_csv(&csv(&runs)).unwrap();
        assert_eq!(back.len(), 2);
        for (a, b) in runs.iter().zip(&back) {
            // `{:e}` writes the shortest text that reads back as the same f64: exact.
            assert_eq!(
                (a.integrator, &a.backend, a.n, a.substeps, a.dt, a.rms, a.max),
                (b.integrator, &b.backend, b.n, b.substeps, b.dt, b.rms, b.max)
            );
            // Cost and time are written rounded (4 and 1 decimals): these two are exact there.
            assert_eq!((a.cost, a.ns_per_substep), (b.cost, b.ns_per_substep));
        }
        let header =
            "integrator,backend,n,substeps_per_frame,dt_s,ns_per_substep,cost_s_per_sim_s,rms_error_m,max_error_m\n";
        let e = read_csv(&format!("{header}leapfrog,cpu,64,8,1e-3,1,1,1,1\n")).unwrap_err();
        assert!(e.to_string().contains("line 2"), "{e}");
        assert!(read_csv(&format!("{header}xpbd,cpu,64\n")).is_err(), "a short row");
    }
}
