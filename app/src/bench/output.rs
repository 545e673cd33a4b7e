//! What `clothlab bench` writes: results.csv, results.json, report.md and the plots.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clothlab_core::SimParams;
use clothlab_core::timing::{CPU_RECORD, CPU_SUBMIT, OverheadPlan, OverheadRow, SUBSTEP, overhead};
use serde::{Deserialize, Serialize};

use super::ladder::LadderCell;
use super::{CHECK_BOUND_PER_SUBSTEP, Cell};

/// One measured quantity: the unit of results.csv and results.json.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// `kernel` (per substep, `frame`/`cpu record`/`cpu submit` per frame), `frame` (whole
    /// simulated and rendered frames) or `overhead` (API micro-benchmarks).
    pub section: String,
    /// Backend (`cpu` … `vulkan`), or the API for `overhead`.
    pub backend: String,
    /// Particles per side; for `overhead`: k dispatches or bytes (0 for the empty submit).
    pub size: u64,
    /// Kernel, `substep`, `sim`/`render`/`frame`, or the overhead benchmark.
    pub label: String,
    /// What clock measured it: `gpu` (timestamps), `cpu` (wall), or the overhead clock.
    pub clock: String,
    /// Samples the statistics are over.
    pub samples: usize,
    /// Median, ns.
    pub median_ns: f64,
    /// Minimum, ns.
    pub min_ns: f64,
    /// Maximum, ns.
    pub max_ns: f64,
    /// Where it ran.
    pub adapter: String,
}

/// The same-workload check of one cell.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Check {
    /// Backend checked.
    pub backend: String,
    /// Particles per side.
    pub n: u32,
    /// The backend compared with (the first that ran at this size).
    pub reference: String,
    /// Largest distance of a probed particle from the reference's, m.
    pub max_dev_m: f64,
    /// The bound, m.
    pub bound_m: f64,
    /// Within the bound.
    pub ok: bool,
}

/// How the run was set up.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Settings {
    /// Substeps per frame.
    pub substeps: u32,
    /// Measured frames per table and cell.
    pub frames: u32,
    /// Unmeasured frames first.
    pub warmup_frames: u32,
    /// Offscreen render target of the frame table.
    pub resolution: (u32, u32),
    /// The simulation parameters (the default scene of each size).
    pub params: SimParams,
    /// The overhead micro-benchmarks.
    pub overhead: OverheadPlan,
}

/// Everything a run measured, as written to results.json.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Results {
    /// clothlab's version.
    pub clothlab: String,
    /// The command line.
    pub command: String,
    /// UTC date of the run.
    pub date: String,
    /// The machine's label (CPU model and threads by default).
    pub machine: String,
    /// Operating system and kernel.
    pub os: String,
    /// wgpu's adapter, if any.
    pub wgpu_adapter: Option<String>,
    /// The Vulkan device, if any.
    pub vulkan_adapter: Option<String>,
    /// The CPU solvers' instruction set, chosen at run time (empty in reports from before
    /// it was recorded).
    #[serde(default)]
    pub cpu_simd: String,
    /// Settings.
    pub settings: Settings,
    /// Every measurement.
    pub rows: Vec<Row>,
    /// Same-workload checks.
    pub checks: Vec<Check>,
    /// Cells skipped (over the time budget), one line each.
    pub skipped: Vec<String>,
    /// Other notes (missing adapters).
    pub notes: Vec<String>,
    /// Wall time of the whole run, s.
    pub seconds: f64,
    /// The optimisation ladder's cells (`--ladder`; empty otherwise).
    #[serde(default)]
    pub ladder: Vec<LadderCell>,
    /// The substep median of every round of every cell run more than once (`--repeat`).
    #[serde(default)]
    pub rounds: Vec<Rounds>,
}

/// The rounds of one cell (`--repeat`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Rounds {
    /// Backend (the cell's name).
    pub backend: String,
    /// Particles per side.
    pub n: u32,
    /// The substep median of each round, ns, in the order run.
    pub substep_ns: Vec<f64>,
}

impl Rounds {
    /// (max − min) / min of the rounds: the run-to-run noise of this cell.
    pub fn spread(&self) -> f64 {
        let lo = self.substep_ns.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = self.substep_ns.iter().copied().fold(0.0, f64::max);
        if lo > 0.0 && lo.is_finite() { (hi - lo) / lo } else { 0.0 }
    }
}

/// What [`Results::new`] is made from.
pub struct Inputs {
    pub machine: String,
    pub wgpu_adapter: Option<String>,
    pub vulkan_adapter: Option<String>,
    pub cpu_simd: String,
    pub params: SimParams,
    pub frames: u32,
    pub warmup_frames: u32,
    pub resolution: (u32, u32),
    pub plan: OverheadPlan,
    pub cells: Vec<Cell>,
    pub overhead: Vec<(String, String, Vec<OverheadRow>)>,
    pub skipped: Vec<String>,
    pub notes: Vec<String>,
    pub seconds: f64,
    pub command: String,
    pub ladder: Vec<LadderCell>,
}

impl Results {
    /// Flattens the cells into rows and checks every cell against its size's reference.
    pub fn new(i: Inputs) -> Self {
        let mut rows = Vec::new();
        for c in &i.cells {
            let gpu = !c.backend.starts_with("cpu");
            for r in &c.kernels {
                let clock = if !gpu || r.label == CPU_RECORD || r.label == CPU_SUBMIT { "cpu" } else { "gpu" };
                rows.push(row("kernel", &c.backend, c.n as u64, r, clock, &c.adapter));
            }
            for r in &c.frames {
                rows.push(row("frame", &c.backend, c.n as u64, r, "cpu", &c.adapter));
            }
        }
        for (api, adapter, list) in &i.overhead {
            for o in list {
                let mut r = row("overhead", api, o.param, &o.stats, &o.stats.label, adapter);
                r.label = o.bench.clone();
                rows.push(r);
            }
        }
        let substeps_run = (i.warmup_frames + 2 * i.frames) as f64 * i.params.substeps as f64;
        let mut checks = Vec::new();
        for c in &i.cells {
            let Some(reference) = i.cells.iter().find(|r| r.n == c.n) else { continue };
            if reference.backend == c.backend {
                continue;
            }
            let max_dev = c
                .probe
                .iter()
                .zip(&reference.probe)
                .map(|(a, b)| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt() as f64)
                .fold(0.0, |m, d| if d.is_nan() { f64::INFINITY } else { m.max(d) });
            let bound = CHECK_BOUND_PER_SUBSTEP * substeps_run;
            checks.push(Check {
                backend: c.backend.clone(),
                n: c.n,
                reference: reference.backend.clone(),
                max_dev_m: max_dev,
                bound_m: bound,
                ok: max_dev <= bound,
            });
        }
        let os = format!(
            "{} {}",
            std::env::consts::OS,
            std::fs::read_to_string("/proc/sys/kernel/osrelease").unwrap_or_default().trim()
        );
        Results {
            clothlab: env!("CARGO_PKG_VERSION").to_owned(),
            command: i.command,
            date: utc_date(),
            machine: i.machine,
            os: os.trim().to_owned(),
            wgpu_adapter: i.wgpu_adapter,
            vulkan_adapter: i.vulkan_adapter,
            cpu_simd: i.cpu_simd,
            settings: Settings {
                substeps: i.params.substeps,
                frames: i.frames,
                warmup_frames: i.warmup_frames,
                resolution: i.resolution,
                params: i.params,
                overhead: i.plan,
            },
            rows,
            checks,
            skipped: i.skipped,
            notes: i.notes,
            seconds: i.seconds,
            ladder: i.ladder,
            rounds: i
                .cells
                .iter()
                .filter(|c| c.runs.len() > 1)
                .map(|c| Rounds { backend: c.backend.clone(), n: c.n, substep_ns: c.runs.clone() })
                .collect(),
        }
    }

    /// The row of `section`/`backend`/`size`/`label` (and `clock` when given).
    pub fn get(&self, section: &str, backend: &str, size: u64, label: &str, clock: Option<&str>) -> Option<&Row> {
        self.rows.iter().find(|r| {
            r.section == section
                && r.backend == backend
                && r.size == size
                && r.label == label
                && clock.is_none_or(|c| r.clock == c)
        })
    }

    /// Backends in the order they ran (overhead APIs excluded).
    pub fn backends(&self) -> Vec<String> {
        let mut v: Vec<String> = Vec::new();
        for r in self.rows.iter().filter(|r| r.section != "overhead") {
            if !v.contains(&r.backend) {
                v.push(r.backend.clone());
            }
        }
        v
    }

    /// Grid sizes measured, ascending.
    pub fn sizes(&self) -> Vec<u64> {
        let mut v: Vec<u64> = self.rows.iter().filter(|r| r.section != "overhead").map(|r| r.size).collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// The size of the per-kernel plot: 500 as in the thesis, else the largest measured
    /// below it, else the smallest.
    pub fn kernel_size(&self) -> Option<u64> {
        let sizes = self.sizes();
        sizes.iter().rev().find(|&&n| n <= 500).or(sizes.first()).copied()
    }
}

fn row(section: &str, backend: &str, size: u64, r: &clothlab_core::TimingRow, clock: &str, adapter: &str) -> Row {
    Row {
        section: section.to_owned(),
        backend: backend.to_owned(),
        size,
        label: r.label.clone(),
        clock: clock.to_owned(),
        samples: r.samples,
        median_ns: r.median_ns,
        min_ns: r.min_ns,
        max_ns: r.max_ns,
        adapter: adapter.to_owned(),
    }
}

/// Today's date (UTC) as YYYY-MM-DD.
fn utc_date() -> String {
    let secs = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0);
    // Days since 1970-01-01 to a civil date (Howard Hinnant's algorithm).
    let z = (secs / 86_400) as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02}")
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) { format!("\"{}\"", s.replace('"', "\"\"")) } else { s.to_owned() }
}

/// The CSV header.
pub const CSV_HEADER: &str = "section,backend,size,label,clock,samples,median_ns,min_ns,max_ns,adapter,machine";

/// results.csv: one row per backend × size × label, machine and adapter in every row.
pub fn csv(results: &Results) -> String {
    let mut s = String::from(CSV_HEADER);
    s.push('\n');
    for r in &results.rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{:.1},{:.1},{:.1},{},{}",
            csv_field(&r.section),
            csv_field(&r.backend),
            r.size,
            csv_field(&r.label),
            csv_field(&r.clock),
            r.samples,
            r.median_ns,
            r.min_ns,
            r.max_ns,
            csv_field(&r.adapter),
            csv_field(&results.machine)
        );
    }
    s
}

fn ms(ns: f64) -> String {
    let v = ns / 1e6;
    if v >= 100.0 {
        format!("{v:.0}")
    } else if v >= 1.0 {
        format!("{v:.2}")
    } else {
        format!("{v:.3}")
    }
}

fn us(ns: f64) -> String {
    let v = ns / 1e3;
    if v >= 100.0 { format!("{v:.0}") } else { format!("{v:.1}") }
}

fn bytes_label(b: u64) -> String {
    if b >= 1 << 20 {
        format!("{} MiB", b >> 20)
    } else if b >= 1 << 10 {
        format!("{} KiB", b >> 10)
    } else {
        format!("{b} B")
    }
}

/// Per-substep CPU cost of a GPU backend: (record + submit per frame) / substeps, ns.
fn cpu_cost_per_substep(r: &Results, backend: &str, n: u64) -> Option<f64> {
    let rec = r.get("kernel", backend, n, CPU_RECORD, None)?.median_ns;
    let sub = r.get("kernel", backend, n, CPU_SUBMIT, None)?.median_ns;
    Some((rec + sub) / r.settings.substeps as f64)
}

/// report.md.
pub fn report(r: &Results) -> String {
    let mut s = String::new();
    let backends = r.backends();
    let sizes = r.sizes();
    let _ = writeln!(s, "# clothlab bench — {}\n", r.machine);
    let _ = writeln!(s, "| | |\n|---|---|");
    let _ = writeln!(s, "| machine | {} |", r.machine);
    let _ = writeln!(s, "| OS | {} |", r.os);
    let _ = writeln!(s, "| wgpu adapter | {} |", r.wgpu_adapter.as_deref().unwrap_or("none"));
    let _ = writeln!(s, "| Vulkan device | {} |", r.vulkan_adapter.as_deref().unwrap_or("none"));
    if !r.cpu_simd.is_empty() {
        let _ = writeln!(s, "| CPU solvers | {} |", r.cpu_simd);
    }
    let _ = writeln!(s, "| clothlab | {} ({}) |", r.clothlab, r.date);
    let _ = writeln!(s, "| command | `{}` |", r.command);
    let st = &r.settings;
    let _ = writeln!(
        s,
        "| workload | default scene, {} substeps per frame; per cell {} warm-up frames, then {} frames timed per kernel ({} substeps), then {} frames simulated + rendered offscreen at {}×{} (GPU backends drawn from their buffers by their own API, CPU backends uploaded to the wgpu renderer) |",
        st.substeps,
        st.warmup_frames,
        st.frames,
        st.frames * st.substeps,
        st.frames,
        st.resolution.0,
        st.resolution.1
    );
    let _ = writeln!(s, "| run time | {:.0} s |\n", r.seconds);
    let _ = writeln!(
        s,
        "Times are medians (min–max in results.csv). GPU kernel times come from timestamp queries, everything else from the CPU clock.\n"
    );

    if let Some(n) = r.kernel_size() {
        let _ = writeln!(s, "## Per-kernel time at {n}×{n} (thesis Figures 7.1–7.4)\n");
        let _ = writeln!(s, "![per-kernel time](kernels.png)\n");
        let _ = writeln!(
            s,
            "Milliseconds per substep (`frame`, `cpu record`, `cpu submit`: per frame; `render`: one offscreen frame).\n"
        );
        let mut labels: Vec<String> = Vec::new();
        for row in r.rows.iter().filter(|x| x.section == "kernel" && x.size == n) {
            if !labels.contains(&row.label) {
                labels.push(row.label.clone());
            }
        }
        labels.push("render".into());
        let _ = writeln!(s, "| kernel | {} |", backends.join(" | "));
        let _ = writeln!(s, "|---|{}", "---:|".repeat(backends.len()));
        for l in &labels {
            let section = if l == "render" { "frame" } else { "kernel" };
            let cells: Vec<String> = backends
                .iter()
                .map(|b| r.get(section, b, n, l, None).map(|x| ms(x.median_ns)).unwrap_or_else(|| "–".into()))
                .collect();
            let _ = writeln!(s, "| {l} | {} |", cells.join(" | "));
        }
        let samples = r.get("kernel", &backends[0], n, SUBSTEP, None).map(|x| x.samples).unwrap_or(0);
        let _ = writeln!(s, "\nSamples per kernel: {samples} substeps.\n");
    }

    let _ = writeln!(s, "## Time per frame and frames per second against grid size (Figures 7.5–7.8)\n");
    let _ = writeln!(s, "![frame time](frame_time.png) ![frames per second](fps.png)\n");
    let _ = writeln!(
        s,
        "Milliseconds per frame ({} substeps + offscreen render), frames per second in brackets.\n",
        st.substeps
    );
    let _ = writeln!(s, "| n | particles | {} |", backends.join(" | "));
    let _ = writeln!(s, "|---:|---:|{}", "---:|".repeat(backends.len()));
    for &n in &sizes {
        let cells: Vec<String> = backends
            .iter()
            .map(|b| {
                r.get("frame", b, n, "frame", None)
                    .map(|x| format!("{} ({:.1})", ms(x.median_ns), 1e9 / x.median_ns))
                    .unwrap_or_else(|| "–".into())
            })
            .collect();
        let _ = writeln!(s, "| {n} | {} | {} |", n * n, cells.join(" | "));
    }
    let _ = writeln!(s, "\nns per particle-substep (GPU substep time, or the CPU solvers' wall time):\n");
    let _ = writeln!(s, "| n | {} |", backends.join(" | "));
    let _ = writeln!(s, "|---:|{}", "---:|".repeat(backends.len()));
    for &n in &sizes {
        let cells: Vec<String> = backends
            .iter()
            .map(|b| {
                r.get("kernel", b, n, SUBSTEP, None)
                    .map(|x| format!("{:.1}", x.median_ns / (n * n) as f64))
                    .unwrap_or_else(|| "–".into())
            })
            .collect();
        let _ = writeln!(s, "| {n} | {} |", cells.join(" | "));
    }

    let apis: Vec<String> = {
        let mut v: Vec<String> = Vec::new();
        for x in r.rows.iter().filter(|x| x.section == "overhead") {
            if !v.contains(&x.backend) {
                v.push(x.backend.clone());
            }
        }
        v
    };
    if !apis.is_empty() {
        let _ = writeln!(s, "\n## API overhead: {}\n", apis.join(" vs "));
        let _ = writeln!(s, "![API overhead](overhead.png)\n");
        let _ = writeln!(
            s,
            "Microseconds, medians of {} samples after {} warm-up runs. `chain k`: k dependent dispatches of one 64-invocation workgroup with a barrier between each two (wgpu: one compute pass, barriers inserted by wgpu; Vulkan: a global memory barrier); `gpu` from timestamps around the chain, `cpu record` recording it, `cpu submit+wait` from submit until the fence. Upload/readback: host → device-local buffer and back, until the data is there.\n",
            st.overhead.samples, st.overhead.warmup
        );
        let _ = writeln!(s, "| benchmark | size | clock | {} |", apis.join(" | "));
        let _ = writeln!(s, "|---|---:|---|{}", "---:|".repeat(apis.len()));
        let mut keys: Vec<(String, u64, String)> = Vec::new();
        for x in r.rows.iter().filter(|x| x.section == "overhead") {
            let k = (x.label.clone(), x.size, x.clock.clone());
            if !keys.contains(&k) {
                keys.push(k);
            }
        }
        for (label, size, clock) in &keys {
            let size_s = match label.as_str() {
                overhead::UPLOAD | overhead::READBACK => bytes_label(*size),
                overhead::CHAIN => format!("k={size}"),
                _ => "–".into(),
            };
            let cells: Vec<String> = apis
                .iter()
                .map(|a| {
                    r.get("overhead", a, *size, label, Some(clock))
                        .map(|x| us(x.median_ns))
                        .unwrap_or_else(|| "–".into())
                })
                .collect();
            let _ = writeln!(s, "| {label} | {size_s} | {clock} | {} |", cells.join(" | "));
        }
        // Per-dispatch cost: slope of the chain's GPU and CPU-record times from k = 1 to the largest k.
        let _ = writeln!(s, "\nPer dispatch (+ barrier), slope from the shortest to the longest chain:\n");
        let _ = writeln!(s, "| clock | {} |", apis.join(" | "));
        let _ = writeln!(s, "|---|{}", "---:|".repeat(apis.len()));
        for clock in [overhead::GPU, overhead::CPU_RECORD, overhead::CPU_SUBMIT_WAIT] {
            let cells: Vec<String> = apis
                .iter()
                .map(|a| chain_slope(r, a, clock).map(|v| format!("{} µs", us(v))).unwrap_or_else(|| "–".into()))
                .collect();
            let _ = writeln!(s, "| {clock} | {} |", cells.join(" | "));
        }
    }

    if !r.rounds.is_empty() {
        let _ = writeln!(
            s,
            "\n## Rounds\n\nEvery cell ran {} rounds, interleaved; its numbers above are the medians of the rounds' medians. The spread, (max − min) / min of the rounds' substep medians, is this machine's run-to-run noise: a difference smaller than it is not a difference.\n",
            r.rounds.iter().map(|x| x.substep_ns.len()).max().unwrap_or(0)
        );
        let _ = writeln!(s, "| backend | n | substep per round (ms) | spread |\n|---|---:|---|---:|");
        for x in &r.rounds {
            let runs: Vec<String> = x.substep_ns.iter().map(|v| format!("{:.2}", v / 1e6)).collect();
            let _ = writeln!(s, "| {} | {} | {} | {:.0} % |", x.backend, x.n, runs.join(" / "), x.spread() * 100.0);
        }
    }
    s.push_str(&super::ladder::report(r));

    let _ = writeln!(s, "\n## Targets\n");
    for line in targets(r) {
        let _ = writeln!(s, "- {line}");
    }

    let _ = writeln!(s, "\n## Same workload\n");
    let _ = writeln!(
        s,
        "Positions of a 5×5 lattice of particles after every cell's {} frames, against the first backend run at that size; bound {:.0e} m per substep.\n",
        st.warmup_frames + 2 * st.frames,
        CHECK_BOUND_PER_SUBSTEP
    );
    let _ = writeln!(
        s,
        "| backend | n | reference | max distance (m) | bound (m) | result |\n|---|---:|---|---:|---:|---|"
    );
    for c in &r.checks {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.2e} | {:.1e} | {} |",
            c.backend,
            c.n,
            c.reference,
            c.max_dev_m,
            c.bound_m,
            if c.ok { "ok" } else { "**FAILED**" }
        );
    }
    if !r.skipped.is_empty() || !r.notes.is_empty() {
        let _ = writeln!(s, "\n## Skipped\n");
        for l in r.notes.iter().chain(&r.skipped) {
            let _ = writeln!(s, "- {l}");
        }
    }
    s
}

/// Per-dispatch cost from the chain: (t(k_max) − t(k_min)) / (k_max − k_min), ns.
pub fn chain_slope(r: &Results, api: &str, clock: &str) -> Option<f64> {
    let pts: Vec<(u64, f64)> = r
        .rows
        .iter()
        .filter(|x| x.section == "overhead" && x.backend == api && x.label == overhead::CHAIN && x.clock == clock)
        .map(|x| (x.size, x.median_ns))
        .collect();
    let lo = pts.iter().min_by_key(|p| p.0)?;
    let hi = pts.iter().max_by_key(|p| p.0)?;
    (hi.0 > lo.0).then(|| (hi.1 - lo.1) / (hi.0 - lo.0) as f64)
}

/// The performance targets, evaluated on this run.
pub fn targets(r: &Results) -> Vec<String> {
    let mut v = Vec::new();
    let sub = |b: &str, n: u64| r.get("kernel", b, n, SUBSTEP, None).map(|x| x.median_ns);
    let sizes = r.sizes();
    // rayon vs serial at 500² (or the largest measured size).
    if let Some(&n) = sizes.iter().rev().find(|&&n| n <= 500)
        && let (Some(a), Some(b)) = (sub("cpu", n), sub("cpu-par", n))
    {
        let x = a / b;
        v.push(format!(
            "CPU rayon ≥ 1.8× CPU serial at 500×500: {x:.2}× at {n}×{n} — {}",
            if n != 500 {
                "not measured at 500"
            } else if x >= 1.8 {
                "met"
            } else {
                "not met"
            }
        ));
    }
    for (api, naive, opt) in [("wgpu", "wgpu-naive", "wgpu"), ("Vulkan", "vulkan-naive", "vulkan")] {
        let pairs: Vec<String> = sizes
            .iter()
            .filter_map(|&n| {
                let (a, b) = (sub(naive, n)?, sub(opt, n)?);
                Some(format!("n={n}: {} vs {} ms{}", ms(b), ms(a), if b < a { "" } else { " (NOT faster)" }))
            })
            .collect();
        if !pairs.is_empty() {
            let all = sizes.iter().all(|&n| match (sub(naive, n), sub(opt, n)) {
                (Some(a), Some(b)) => b < a,
                _ => true,
            });
            v.push(format!(
                "Optimized < naive per substep on {api}: {} — {}",
                pairs.join("; "),
                if all { "met" } else { "not met" }
            ));
        }
    }
    let pairs: Vec<(u64, f64, f64)> = sizes
        .iter()
        .filter_map(|&n| Some((n, cpu_cost_per_substep(r, "vulkan", n)?, cpu_cost_per_substep(r, "wgpu", n)?)))
        .collect();
    if !pairs.is_empty() {
        let text: Vec<String> =
            pairs.iter().map(|(n, vk, wg)| format!("n={n}: {} vs {} µs", us(*vk), us(*wg))).collect();
        let all = pairs.iter().all(|(_, vk, wg)| vk < wg);
        v.push(format!(
            "Vulkan CPU cost per substep (record + submit) < wgpu's: {} — {}",
            text.join("; "),
            if all { "met" } else { "not met" }
        ));
    }
    if v.is_empty() {
        v.push("no target applies to the backends measured".into());
    }
    v
}

/// Writes `bytes` to `dir/name` and notes the path in `files`.
fn put(dir: &Path, files: &mut Vec<PathBuf>, name: &str, bytes: &[u8]) -> Result<()> {
    let p = dir.join(name);
    std::fs::write(&p, bytes).with_context(|| format!("cannot write {}", p.display()))?;
    files.push(p);
    Ok(())
}

/// Writes every file into `dir` and returns their paths.
pub fn write_all(results: &Results, dir: &Path) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    put(dir, &mut files, "results.csv", csv(results).as_bytes())?;
    put(dir, &mut files, "results.json", serde_json::to_string_pretty(results)?.as_bytes())?;
    files.extend(write_report(results, dir)?);
    Ok(files)
}

/// Writes report.md and the plots into `dir` and returns their paths.
pub fn write_report(results: &Results, dir: &Path) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    put(dir, &mut files, "report.md", report(results).as_bytes())?;
    for (name, svg, png) in super::plot::all(results)? {
        put(dir, &mut files, &format!("{name}.svg"), svg.as_bytes())?;
        put(dir, &mut files, &format!("{name}.png"), &png)?;
    }
    Ok(files)
}

/// The results of a made-up run (the report's tests): 10 frames of 16 substeps per cell.
#[cfg(test)]
pub(crate) fn test_results(
    cells: Vec<Cell>,
    overhead: Vec<(String, String, Vec<OverheadRow>)>,
    ladder: Vec<LadderCell>,
) -> Results {
    Results::new(Inputs {
        machine: "test machine".into(),
        wgpu_adapter: None,
        vulkan_adapter: None,
        cpu_simd: "fused sweep on AVX2, 8 lanes".into(),
        params: SimParams::default(),
        frames: 10,
        warmup_frames: 3,
        resolution: (64, 64),
        plan: OverheadPlan::default(),
        cells,
        overhead,
        skipped: vec![],
        notes: vec![],
        seconds: 1.0,
        command: "test".into(),
        ladder,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use clothlab_core::TimingRow;

    fn timing(label: &str, ns: f64) -> TimingRow {
        TimingRow { label: label.into(), samples: 16, median_ns: ns, min_ns: ns * 0.9, max_ns: ns * 1.2 }
    }

    fn cell(backend: &str, n: u32, substep_ns: f64, shift_m: f32) -> Cell {
        Cell {
            backend: backend.into(),
            n,
            adapter: "test".into(),
            kernels: vec![
                timing(SUBSTEP, substep_ns),
                timing(CPU_RECORD, substep_ns / 10.0),
                timing(CPU_SUBMIT, substep_ns / 100.0),
            ],
            frames: vec![timing("frame", 16.0 * substep_ns)],
            probe: (0..25).map(|i| [i as f32 * 0.1 + shift_m, 1.0, 0.0]).collect(),
            seconds: 1.0,
            runs: vec![],
        }
    }

    fn results(cells: Vec<Cell>, overhead: Vec<(String, String, Vec<OverheadRow>)>) -> Results {
        test_results(cells, overhead, vec![])
    }

    #[test]
    fn a_backend_that_ends_elsewhere_fails_the_same_workload_check() {
        // (3 + 2·10) frames × 16 substeps × 1e-5 m = 3.68 mm allowed.
        let r = results(
            vec![cell("cpu", 64, 1e5, 0.0), cell("wgpu", 64, 1e4, 0.001), cell("vulkan", 64, 1e4, 0.01)],
            vec![],
        );
        let by = |b: &str| r.checks.iter().find(|c| c.backend == b).unwrap();
        assert!((by("wgpu").bound_m - 3.68e-3).abs() < 1e-9);
        assert!(by("wgpu").ok && (by("wgpu").max_dev_m - 1e-3).abs() < 1e-6, "{:?}", by("wgpu"));
        assert!(!by("vulkan").ok, "1 cm off must fail: {:?}", by("vulkan"));
        assert!(report(&r).contains("**FAILED**"));
        // A NaN position is never within the bound.
        let mut bad = cell("cpu-par", 64, 1e5, 0.0);
        bad.probe[3][1] = f32::NAN;
        let r = results(vec![cell("cpu", 64, 1e5, 0.0), bad], vec![]);
        assert!(!r.checks[0].ok);
    }

    #[test]
    fn targets_compare_the_right_rows() {
        let r = results(
            vec![
                cell("cpu", 500, 2e7, 0.0),
                cell("cpu-par", 500, 1e7, 0.0),
                cell("wgpu-naive", 500, 9e6, 0.0),
                cell("wgpu", 500, 8e6, 0.0),
                cell("vulkan-naive", 500, 5e6, 0.0),
                cell("vulkan", 500, 6e6, 0.0),
            ],
            vec![],
        );
        let t = targets(&r).join("\n");
        assert!(t.contains("2.00× at 500×500 — met"), "{t}");
        assert!(t.contains("on wgpu: n=500: 8.00 vs 9.00 ms — met"), "{t}");
        assert!(t.contains("on Vulkan: n=500: 6.00 vs 5.00 ms (NOT faster) — not met"), "{t}");
        // Vulkan (6e5 + 6e4) / 16 = 41.25 µs vs wgpu (8e5 + 8e4) / 16 = 55 µs per substep.
        assert!(t.contains("n=500: 41.2 vs 55.0 µs — met"), "{t}");
    }

    #[test]
    fn chain_slope_is_the_cost_per_added_dispatch() {
        let rows = [1u64, 8, 64]
            .iter()
            .map(|&k| OverheadRow {
                bench: overhead::CHAIN.into(),
                param: k,
                stats: timing(overhead::GPU, 5_000.0 + 2_000.0 * k as f64),
            })
            .collect();
        let r = results(vec![], vec![("vulkan".into(), "test".into(), rows)]);
        let slope = chain_slope(&r, "vulkan", overhead::GPU).unwrap();
        assert!((slope - 2_000.0).abs() < 1e-9, "{slope}");
        assert!(chain_slope(&r, "wgpu", overhead::GPU).is_none());
        let csv = csv(&r);
        assert_eq!(csv.lines().count(), 4, "{csv}");
        assert!(csv.lines().nth(1).unwrap().starts_with("overhead,vulkan,1,chain,gpu,16,7000.0,"), "{csv}");
    }
}
