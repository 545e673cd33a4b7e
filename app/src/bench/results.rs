//! The data of a `clothlab bench` run: the measured cells, the rows of results.csv and
//! results.json, the ladder's cells. The measurement (`bench::mod`) fills it; the writers
//! (`output`: CSV, JSON, report.md; `ladder`: the ladder's tables; `plot`: the figures)
//! only read it, so none of them imports another's data.

use clothlab::core::SimParams;
use clothlab::core::timing::{CPU_RECORD, CPU_SUBMIT, OverheadPlan, OverheadRow, overhead};
use serde::{Deserialize, Serialize};

/// Bound on a sampled particle's distance from the reference backend's after the run,
/// per simulated substep, m. Float summation order makes backends drift apart slowly (core::
/// validate bounds a 200-substep rollout by 1e-6 m per substep); contacts and strain
/// limiting let that drift grow over thousands of substeps: on an H100 (NVIDIA 580, which
/// rounds and fuses otherwise than the CPU) every GPU backend ended 2.4–7.1 cm from the
/// CPU's after the default scene's 2142 substeps at n = 128–2048, where lavapipe matches
/// the CPU bit for bit. So the check allows 50× that rate (10.7 cm over such a run),
/// still below what a skipped substep or kernel moves a falling cloth (about a
/// millimetre per substep at the speeds of the default scene).
pub const CHECK_BOUND_PER_SUBSTEP: f64 = 5e-5;

pub use clothlab::bench::Cell;

/// One rung of one API's ladder at one size, as measured (results.json keeps them).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct LadderCell {
    /// `wgpu` or `vulkan`.
    pub api: String,
    /// Particles per side.
    pub n: u32,
    /// Position on the ladder (0: naive); the thesis preset comes after the last rung.
    pub index: usize,
    /// `naive`, `+submit=frame`, …, or `thesis (preset)`.
    pub rung: String,
    /// The cell's backend name (the solver's: `vulkan-naive+submit=frame`, …).
    pub backend: String,
    /// Every switch of the variant, `key=value,…`.
    pub switches: String,
    /// Why the rung did not run on this adapter (the switch it lacks).
    pub skipped: Option<String>,
    /// Dispatches per substep.
    pub dispatches: usize,
    /// Compulsory bytes per substep (`clothlab::engine::kernels::compulsory_bytes`).
    pub bytes: u64,
}

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
    /// The simulation parameters (the scene's at each size).
    pub params: SimParams,
    /// The overhead micro-benchmarks.
    pub overhead: OverheadPlan,
    /// The scene measured: its title and file, or "default scene" (reports written before
    /// it was recorded: that is what they measured).
    #[serde(default = "default_scene_label")]
    pub scene: String,
}

fn default_scene_label() -> String {
    "default scene".into()
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
    /// The OpenGL context, if any (absent in reports from before GL).
    #[serde(default)]
    pub gl_adapter: Option<String>,
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
    /// The searches of the contact between triangles, for the cells that have it.
    #[serde(default)]
    pub searches: Vec<Searches>,
    /// Set when the run was stopped before its end: `after k of N cells`.
    #[serde(default)]
    pub interrupted: Option<String>,
    /// The GPU memory's peak bandwidth, GB/s (`--peak-gbps`; else [`known_peak`] of the
    /// adapters' names when the report is written).
    #[serde(default)]
    pub peak_gbps: Option<f64>,
}

/// Peak memory bandwidth of common compute cards, GB/s (the makers' data sheets), by a
/// substring of the adapter's name as the drivers give it (first match wins: the more
/// specific names first). The H100 80GB HBM3 and the H200 are the cards the reports have
/// met (docs/bench/h100, h200); a card not listed takes `--peak-gbps`.
pub const KNOWN_PEAKS: [(&str, f64); 11] = [
    ("H100 80GB HBM3", 3350.0),
    ("H100 PCIe", 2000.0),
    ("H100 NVL", 3900.0),
    ("H200", 4800.0),
    ("A100-SXM4-80GB", 2039.0),
    ("A100 80GB PCIe", 1935.0),
    ("A100-SXM4-40GB", 1555.0),
    ("A100-PCIE-40GB", 1555.0),
    ("L40S", 864.0),
    ("RTX 4090", 1008.0),
    ("RTX 3090", 936.0),
];

/// The peak bandwidth of `r`'s GPU: `--peak-gbps`, else that of a known card its adapters
/// name.
pub fn known_peak(r: &Results) -> Option<f64> {
    r.peak_gbps.or_else(|| {
        let names = [&r.vulkan_adapter, &r.wgpu_adapter, &r.gl_adapter];
        KNOWN_PEAKS
            .iter()
            .find(|(card, _)| names.iter().any(|a| a.as_deref().is_some_and(|a| a.contains(card))))
            .map(|&(_, gbps)| gbps)
    })
}

/// The contact between triangles' searches a frame of one cell.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Searches {
    /// Backend (the cell's name).
    pub backend: String,
    /// Particles per side.
    pub n: u32,
    /// Full searches and partial ones a frame, over the per-kernel frames.
    pub per_frame: [f64; 2],
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
    pub gl_adapter: Option<String>,
    pub cpu_simd: String,
    pub params: SimParams,
    pub scene: String,
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
    pub interrupted: Option<String>,
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
            gl_adapter: i.gl_adapter,
            cpu_simd: i.cpu_simd,
            settings: Settings {
                substeps: i.params.substeps,
                frames: i.frames,
                warmup_frames: i.warmup_frames,
                resolution: i.resolution,
                params: i.params,
                overhead: i.plan,
                scene: i.scene,
            },
            rows,
            checks,
            skipped: i.skipped,
            notes: i.notes,
            seconds: i.seconds,
            ladder: i.ladder,
            interrupted: i.interrupted,
            peak_gbps: None,
            rounds: i
                .cells
                .iter()
                .filter(|c| c.runs.len() > 1)
                .map(|c| Rounds { backend: c.backend.clone(), n: c.n, substep_ns: c.runs.clone() })
                .collect(),
            searches: i
                .cells
                .iter()
                .filter_map(|c| c.searches.map(|per_frame| Searches { backend: c.backend.clone(), n: c.n, per_frame }))
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

fn row(section: &str, backend: &str, size: u64, r: &clothlab::core::TimingRow, clock: &str, adapter: &str) -> Row {
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
        gl_adapter: None,
        cpu_simd: "fused sweep on AVX2, 8 lanes".into(),
        params: SimParams::default(),
        scene: default_scene_label(),
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
        interrupted: None,
    })
}

#[cfg(test)]
mod peak_tests {
    use super::*;

    #[test]
    fn a_known_card_gets_its_data_sheet_peak_and_the_flag_wins() {
        let mut r = test_results(vec![], vec![], vec![]);
        assert_eq!(known_peak(&r), None, "no adapter named: no bound");
        r.gl_adapter = Some("llvmpipe (LLVM 15.0.6, 256 bits)".into());
        assert_eq!(known_peak(&r), None, "llvmpipe has no data sheet");
        for (name, gbps) in [
            ("NVIDIA H100 80GB HBM3", 3350.0),
            ("NVIDIA A100-SXM4-80GB", 2039.0),
            ("NVIDIA A100 80GB PCIe", 1935.0),
            ("NVIDIA GeForce RTX 4090", 1008.0),
        ] {
            r.vulkan_adapter = Some(name.into());
            assert_eq!(known_peak(&r), Some(gbps), "{name}");
        }
        r.peak_gbps = Some(1234.0);
        assert_eq!(known_peak(&r), Some(1234.0), "--peak-gbps wins over the table");
    }
}
