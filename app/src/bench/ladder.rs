//! `clothlab bench --ladder`: from `naive` to the fastest combination, one switch at a
//! time (`clothlab::engine::variant::LADDER`), on each GPU API at each size, plus the
//! `thesis` preset; per rung the substep, per-kernel, CPU record/submit and frame times
//! (the cells of the ordinary benchmark), what the rung bought, and which resource bounds
//! it on this adapter.

use std::fmt::Write as _;

use clothlab::core::timing::{CPU_RECORD, CPU_SUBMIT, FRAME, SUBSTEP};

use super::results::{LadderCell, Results, chain_slope, known_peak};
use clothlab::engine::recipe::STATE_BYTES;

/// The thesis's own figure for its optimized CUDA port against the direct one
/// (ch. 7: "about 4 frames per second more").
pub const THESIS_FPS_GAIN: f64 = 4.0;

/// Share of a substep above which a resource is named as what bounds it.
const BOUND_SHARE: f64 = 0.5;
/// Fraction of the best achieved bandwidth above which a rung counts as memory bound.
const MEMORY_SHARE: f64 = 0.6;

/// A rung's measured numbers.
struct Measured {
    substep_ns: f64,
    frame_ns: Option<f64>,
    sim_ns: Option<f64>,
    record_ns: Option<f64>,
    submit_ns: Option<f64>,
}

fn measured(r: &Results, c: &LadderCell) -> Option<Measured> {
    let n = c.n as u64;
    let kernel = |label: &str| r.get("kernel", &c.backend, n, label, None).map(|x| x.median_ns);
    let frame = |label: &str| r.get("frame", &c.backend, n, label, None).map(|x| x.median_ns);
    Some(Measured {
        substep_ns: kernel(SUBSTEP)?,
        frame_ns: frame(FRAME),
        sim_ns: frame("sim"),
        record_ns: kernel(CPU_RECORD),
        submit_ns: kernel(CPU_SUBMIT),
    })
}

/// Which resource bounds a rung, and the numbers that decided it.
fn bound(r: &Results, c: &LadderCell, m: &Measured, best_gbs: f64) -> String {
    let substeps = r.settings.substeps as f64;
    // 1. Dispatch overhead: dispatches × the API's cost per dispatch (the slope of the
    //    dispatch-chain benchmark, GPU clock) against the substep's GPU time.
    if let Some(per) = chain_slope(r, &c.api, "gpu") {
        let share = c.dispatches as f64 * per / m.substep_ns;
        if share >= BOUND_SHARE {
            return format!(
                "dispatch overhead ({} × {:.1} µs = {:.0} % of the substep)",
                c.dispatches,
                per / 1e3,
                share * 100.0
            );
        }
    }
    // 2. Submission and CPU: the wall time of a frame's simulation beyond its GPU time.
    if let Some(sim) = m.sim_ns {
        let gpu = m.substep_ns * substeps;
        let share = (sim - gpu) / sim;
        if share >= BOUND_SHARE {
            return format!("submission / CPU ({:.0} % of the frame's wall time is outside the GPU's)", share * 100.0);
        }
    }
    // 3. Memory or arithmetic: compulsory bytes per GPU second against the best any rung
    //    of this API reached (this adapter's measured ceiling, not a data-sheet peak).
    let gbs = c.bytes as f64 / m.substep_ns;
    if best_gbs > 0.0 && gbs >= MEMORY_SHARE * best_gbs {
        format!("memory ({gbs:.1} GB/s, {:.0} % of the best rung's {best_gbs:.1})", gbs / best_gbs * 100.0)
    } else {
        format!(
            "arithmetic / latency ({gbs:.1} GB/s, {:.0} % of the best rung's {best_gbs:.1})",
            gbs / best_gbs.max(1e-9) * 100.0
        )
    }
}

/// The ladder section of the report: per API and size a table of the rungs, and the
/// thesis preset's gain over naive beside the thesis's.
pub fn report(r: &Results) -> String {
    let mut s = String::new();
    if r.ladder.is_empty() {
        return s;
    }
    let _ = writeln!(s, "\n## Optimisation ladder\n");
    let _ = writeln!(
        s,
        "From `naive`, one switch at a time (each rung keeps the ones before); `thesis` is the thesis's optimized CUDA recipe as a preset. Substep: GPU timestamps, median; frame: simulated and drawn offscreen, wall clock. *Bound* names what limits the rung on this adapter: **dispatch overhead** when dispatches × the API's cost per dispatch (the dispatch-chain benchmark's slope) is ≥ {:.0} % of the substep; else **submission / CPU** when ≥ {:.0} % of the frame's wall time lies outside the GPU's; else **memory** when the compulsory bytes per second (every buffer a kernel's row names, once) reach ≥ {:.0} % of the best any rung of this API reached, **arithmetic / latency** otherwise.\n",
        BOUND_SHARE * 100.0,
        BOUND_SHARE * 100.0,
        MEMORY_SHARE * 100.0
    );
    let mut keys: Vec<(String, u32)> = Vec::new();
    for c in &r.ladder {
        if !keys.contains(&(c.api.clone(), c.n)) {
            keys.push((c.api.clone(), c.n));
        }
    }
    for (api, n) in keys {
        let cells: Vec<&LadderCell> = r.ladder.iter().filter(|c| c.api == api && c.n == n).collect();
        let best_gbs = r
            .ladder
            .iter()
            .filter(|c| c.api == api)
            .filter_map(|c| measured(r, c).map(|m| c.bytes as f64 / m.substep_ns))
            .fold(0.0, f64::max);
        let _ = writeln!(s, "### {api}, n = {n}\n");
        let _ = writeln!(s, "![what each optimisation buys, {api}, n = {n}](ladder_{api}_{n}.png)\n");
        let peak = known_peak(r);
        // The state's compulsory traffic at the card's peak: no substep can be faster.
        let floor_ns = peak.map(|gbps| STATE_BYTES as f64 * (n as f64).powi(2) / gbps);
        match (peak, floor_ns) {
            (Some(gbps), Some(ns)) => {
                let _ = writeln!(
                    s,
                    "Bytes: each rung's compulsory bytes per particle-substep (every buffer its kernels' rows name, once; the tiles' halos read again), against the state's {STATE_BYTES} B (positions and velocities read and written once): at the memory's {gbps:.0} GB/s peak no substep of n = {n} takes less than {:.4} ms.\n",
                    ns / 1e6
                );
            }
            _ => {
                let _ = writeln!(
                    s,
                    "Bytes: each rung's compulsory bytes per particle-substep (every buffer its kernels' rows name, once; the tiles' halos read again), against the state's {STATE_BYTES} B (positions and velocities read and written once); no peak bandwidth known for this adapter (`--peak-gbps`).\n"
                );
            }
        }
        let _ = writeln!(
            s,
            "| rung | substep ms | vs previous | vs naive | ns / particle | B / particle | × the bound | frame ms (fps) | cpu record µs | cpu submit µs | dispatches | kernels (µs) | bound |"
        );
        let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|");
        let naive = cells.iter().find(|c| c.index == 0).and_then(|c| measured(r, c));
        let mut prev: Option<f64> = None;
        let mut prev_backend: Option<String> = None;
        let np = (n as f64).powi(2);
        for c in &cells {
            if let Some(why) = &c.skipped {
                let _ = writeln!(s, "| {} | – | – | – | – | – | – | – | – | – | – | skipped: {why} | – |", c.rung);
                continue;
            }
            let Some(m) = measured(r, c) else { continue };
            let kernels: Vec<String> = r
                .rows
                .iter()
                .filter(|x| x.section == "kernel" && x.backend == c.backend && x.size == n as u64)
                .filter(|x| ![SUBSTEP, FRAME, CPU_RECORD, CPU_SUBMIT].contains(&x.label.as_str()))
                .map(|x| format!("{} {:.0}", x.label, x.median_ns / 1e3))
                .collect();
            let thesis = c.rung.starts_with("thesis");
            // A change inside the rounds' spread (of this rung or the one before) is noise.
            let spread =
                |backend: &str| r.rounds.iter().find(|x| x.backend == backend && x.n == c.n).map(|x| x.spread());
            let noise = match (spread(&c.backend), prev_backend.as_deref().and_then(spread)) {
                (Some(a), Some(b)) => Some(a.max(b)),
                (a, b) => a.or(b),
            };
            let vs_prev = match (prev, thesis) {
                (Some(p), false) => {
                    let change = m.substep_ns / p - 1.0;
                    let within = noise.is_some_and(|nz| change.abs() < nz);
                    format!("{:+.0} %{}", change * 100.0, if within { " (noise)" } else { "" })
                }
                _ => "–".into(),
            };
            let vs_naive = naive.as_ref().map(|a| format!("{:.2}×", a.substep_ns / m.substep_ns)).unwrap_or_default();
            let frame = m.frame_ns.map(|f| format!("{:.1} ({:.1})", f / 1e6, 1e9 / f)).unwrap_or_else(|| "–".into());
            let us = |v: Option<f64>| v.map(|v| format!("{:.0}", v / 1e3)).unwrap_or_else(|| "–".into());
            let times = floor_ns.map(|f| format!("{:.1}×", m.substep_ns / f)).unwrap_or_else(|| "–".into());
            let _ = writeln!(
                s,
                "| {} | {:.3} | {vs_prev} | {vs_naive} | {:.1} | {:.0} | {times} | {frame} | {} | {} | {} | {} | {} |",
                if thesis { format!("**{}**", c.rung) } else { c.rung.clone() },
                m.substep_ns / 1e6,
                m.substep_ns / np,
                c.bytes as f64 / np,
                us(m.record_ns),
                us(m.submit_ns),
                c.dispatches,
                kernels.join(", "),
                bound(r, c, &m, best_gbs)
            );
            if !thesis {
                prev = Some(m.substep_ns);
                prev_backend = Some(c.backend.clone());
            }
        }
        let fastest = cells
            .iter()
            .filter(|c| c.skipped.is_none())
            .filter_map(|c| measured(r, c).map(|m| (c, m.substep_ns)))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((c, ns)) = fastest {
            let _ = writeln!(s, "\nFastest: {} ({}) at {:.1} ns per particle-substep.", c.rung, c.switches, ns / np);
        }
        let fps = |c: Option<&&LadderCell>| c.and_then(|c| measured(r, c)).and_then(|m| m.frame_ns).map(|f| 1e9 / f);
        let thesis = cells.iter().find(|c| c.rung.starts_with("thesis"));
        if let (Some(a), Some(b)) = (fps(cells.iter().find(|c| c.index == 0)), fps(thesis)) {
            let _ = writeln!(
                s,
                "The thesis preset draws {b:.2} fps against naive's {a:.2}: {:+.2} fps (the thesis: about {THESIS_FPS_GAIN:.0} fps more on its GPUs at its sizes).\n",
                b - a
            );
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::results::{Cell, test_results as results};
    use clothlab::core::TimingRow;
    use clothlab::core::timing::{OverheadRow, overhead};

    fn t(label: &str, ns: f64) -> TimingRow {
        TimingRow { label: label.into(), samples: 8, median_ns: ns, min_ns: ns, max_ns: ns }
    }

    fn cell(backend: &str, substep_ns: f64, sim_ns: f64) -> Cell {
        Cell {
            backend: backend.into(),
            n: 100,
            adapter: "test".into(),
            kernels: vec![t(SUBSTEP, substep_ns), t(CPU_RECORD, 1e3), t(CPU_SUBMIT, 1e3)],
            frames: vec![t("sim", sim_ns), t(FRAME, sim_ns + 1e6)],
            probe: vec![[0.0; 3]; 25],
            seconds: 1.0,
            runs: vec![],
            searches: None,
        }
    }

    fn rung(index: usize, backend: &str, dispatches: usize, bytes: u64) -> LadderCell {
        LadderCell {
            api: "vulkan".into(),
            n: 100,
            index,
            rung: if index == 0 { "naive".into() } else { format!("+rung{index}") },
            backend: backend.into(),
            switches: String::new(),
            skipped: None,
            dispatches,
            bytes,
        }
    }

    #[test]
    fn each_rung_is_bound_by_what_its_numbers_say() {
        // Chain: 10 µs per dispatch. Substeps of 16 per frame.
        let chain = [1u64, 64]
            .iter()
            .map(|&k| OverheadRow {
                bench: overhead::CHAIN.into(),
                param: k,
                stats: t(overhead::GPU, 1e3 + 1e4 * k as f64),
            })
            .collect();
        let cells = vec![
            // 7 dispatches × 10 µs = 70 µs of a 100 µs substep: dispatch overhead.
            cell("a", 1e5, 16.0 * 1e5),
            // 1 dispatch (10 %), but the frame's wall is 4× its GPU time: submission.
            cell("b", 1e5, 4.0 * 16.0 * 1e5),
            // 1 dispatch, GPU-bound, 1e6 bytes / 1e5 ns = 10 GB/s: the best, memory.
            cell("c", 1e5, 16.0 * 1e5),
            // 1 dispatch, GPU-bound, 2 GB/s (20 % of the best): arithmetic / latency.
            cell("d", 1e5, 16.0 * 1e5),
        ];
        let ladder = vec![rung(0, "a", 7, 0), rung(1, "b", 1, 0), rung(2, "c", 1, 1_000_000), rung(3, "d", 1, 200_000)];
        let r = results(cells, vec![("vulkan".into(), "test".into(), chain)], ladder);
        let text = report(&r);
        let row = |name: &str| text.lines().find(|l| l.starts_with(&format!("| {name} |"))).unwrap().to_string();
        assert!(row("naive").contains("dispatch overhead (7 × 10.0 µs = 70 % of the substep)"), "{}", row("naive"));
        assert!(row("+rung1").contains("submission / CPU (75 %"), "{}", row("+rung1"));
        assert!(row("+rung2").contains("memory (10.0 GB/s, 100 %"), "{}", row("+rung2"));
        assert!(row("+rung3").contains("arithmetic / latency (2.0 GB/s, 20 %"), "{}", row("+rung3"));
    }

    #[test]
    fn a_change_inside_the_rounds_spread_is_called_noise() {
        // Rung 1 is 5 % faster than naive, whose rounds spread 10 %: noise. Rung 2 is 50 %
        // faster again: not.
        let mut a = cell("a", 1.00e5, 16.0 * 1e5);
        a.runs = vec![1.00e5, 1.10e5, 1.05e5];
        let mut b = cell("b", 0.95e5, 16.0 * 1e5);
        b.runs = vec![0.95e5, 0.96e5, 0.94e5];
        let mut c = cell("c", 0.475e5, 16.0 * 1e5);
        c.runs = vec![0.475e5, 0.48e5, 0.47e5];
        let r = results(vec![a, b, c], vec![], vec![rung(0, "a", 1, 0), rung(1, "b", 1, 0), rung(2, "c", 1, 0)]);
        assert_eq!(r.rounds.len(), 3);
        assert!((r.rounds[0].spread() - 0.10).abs() < 1e-12, "{}", r.rounds[0].spread());
        let text = report(&r);
        let row = |name: &str| text.lines().find(|l| l.starts_with(&format!("| {name} |"))).unwrap().to_string();
        assert!(row("+rung1").contains("| -5 % (noise) |"), "{}", row("+rung1"));
        assert!(row("+rung2").contains("| -50 % |"), "{}", row("+rung2"));
    }

    #[test]
    fn rounds_merge_to_the_median_of_their_medians() {
        let rounds: Vec<Cell> = [3.0e5, 1.0e5, 2.0e5].iter().map(|&ns| cell("a", ns, 16.0 * ns)).collect();
        let m = Cell::merge(rounds).unwrap();
        let sub = m.kernels.iter().find(|r| r.label == SUBSTEP).unwrap();
        assert_eq!((sub.median_ns, sub.min_ns, sub.max_ns, sub.samples), (2.0e5, 1.0e5, 3.0e5, 24));
        assert_eq!(m.runs, vec![3.0e5, 1.0e5, 2.0e5]);
        assert_eq!(m.seconds, 3.0);
    }
}
