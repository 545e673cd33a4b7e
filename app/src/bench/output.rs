//! What `clothlab bench` writes: results.csv, results.json, report.md and the plots.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Result;
use clothlab::core::timing::{CPU_RECORD, CPU_SUBMIT, SUBSTEP, overhead};

use super::results::{CHECK_BOUND_PER_SUBSTEP, Results, chain_slope};

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

/// The report's columns: the backends, in groups. A plain run is one group of backends
/// under their own names; a ladder run (`--ladder`) has a group per API whose columns are
/// the rungs' short labels (`naive`, `+submit=frame`, `thesis`), with the full solver
/// names in a legend, so that no table has thirty columns named by every switch.
struct Columns {
    /// (group title, [(backend, column label)]); the title is empty for a plain run.
    groups: Vec<(String, Vec<(String, String)>)>,
}

impl Columns {
    fn of(r: &Results) -> Self {
        let backends = r.backends();
        if r.ladder.is_empty() {
            return Columns {
                groups: vec![(String::new(), backends.iter().map(|b| (b.clone(), b.clone())).collect())],
            };
        }
        let mut groups: Vec<(String, Vec<(String, String)>)> = Vec::new();
        for b in &backends {
            let (title, label) = match r.ladder.iter().find(|c| &c.backend == b) {
                Some(c) => (c.api.clone(), c.rung.trim_end_matches(" (preset)").to_owned()),
                None => ("other".to_owned(), b.clone()),
            };
            match groups.iter_mut().find(|g| g.0 == title) {
                Some(g) if !g.1.iter().any(|x| x.0 == *b) => g.1.push((b.clone(), label)),
                Some(_) => {}
                None => groups.push((title, vec![(b.clone(), label)])),
            }
        }
        Columns { groups }
    }

    /// A backend's short name outside its group's table (`vulkan +submit=frame`).
    fn name(&self, backend: &str) -> String {
        for (title, cols) in &self.groups {
            if let Some((_, label)) = cols.iter().find(|c| c.0 == backend) {
                return if title.is_empty() || title == "other" { label.clone() } else { format!("{title} {label}") };
            }
        }
        backend.to_owned()
    }

    /// Writes one table per group: a heading (`### title`) where there are groups, the
    /// header `first | columns…`, and a row per `rows` item whose cells `cell` gives.
    fn tables<K>(
        &self,
        s: &mut String,
        first: &[&str],
        rows: &[K],
        row_head: impl Fn(&K) -> Vec<String>,
        cell: impl Fn(&K, &str) -> String,
    ) {
        for (title, cols) in &self.groups {
            if !title.is_empty() {
                let _ = writeln!(s, "**{title}**\n");
            }
            let labels: Vec<&str> = cols.iter().map(|c| c.1.as_str()).collect();
            let _ = writeln!(s, "| {} | {} |", first.join(" | "), labels.join(" | "));
            let align = if first[0] == "n" { "---:|" } else { "---|" };
            let _ = writeln!(s, "|{}{}{}", align, "---:|".repeat(first.len() - 1), "---:|".repeat(cols.len()));
            for k in rows {
                let cells: Vec<String> = cols.iter().map(|c| cell(k, &c.0)).collect();
                let _ = writeln!(s, "| {} | {} |", row_head(k).join(" | "), cells.join(" | "));
            }
            let _ = writeln!(s);
        }
    }

    /// The legend of a ladder run: each column's solver and its switches.
    fn legend(&self, r: &Results) -> String {
        let mut s = String::new();
        if r.ladder.is_empty() {
            return s;
        }
        let _ = writeln!(
            s,
            "Columns of a ladder run are its rungs, one table per API; each is the solver below (every switch: results.json, `ladder[].switches`).\n"
        );
        let _ = writeln!(s, "| API | column | solver |\n|---|---|---|");
        for (title, cols) in &self.groups {
            for (b, label) in cols {
                let _ = writeln!(s, "| {title} | {label} | `{b}` |");
            }
        }
        let _ = writeln!(s);
        s
    }
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
    let _ = writeln!(s, "| OpenGL context | {} |", r.gl_adapter.as_deref().unwrap_or("none"));
    if !r.cpu_simd.is_empty() {
        let _ = writeln!(s, "| CPU solvers | {} |", r.cpu_simd);
    }
    let _ = writeln!(s, "| clothlab | {} ({}) |", r.clothlab, r.date);
    let _ = writeln!(s, "| command | `{}` |", r.command);
    let st = &r.settings;
    let _ = writeln!(
        s,
        "| workload | {}, {} substeps per frame; per cell {} warm-up frames, then {} frames timed per kernel ({} substeps), then {} frames simulated + rendered offscreen at {}×{} (GPU backends drawn from their buffers by their own API; CPU backends' state uploaded to the wgpu renderer) |",
        st.scene,
        st.substeps,
        st.warmup_frames,
        st.frames,
        st.frames * st.substeps,
        st.frames,
        st.resolution.0,
        st.resolution.1
    );
    let _ = writeln!(s, "| run time | {:.0} s |\n", r.seconds);
    if let Some(what) = &r.interrupted {
        let _ = writeln!(
            s,
            "**Interrupted {what}**: the tables below hold the cells it finished; `clothlab bench --resume <this folder>` with the same options measures the rest.\n"
        );
    }
    let _ = writeln!(
        s,
        "Times are medians (min–max in results.csv). GPU kernel times come from timestamp queries, everything else from the CPU clock.\n"
    );
    let cols = Columns::of(r);
    s.push_str(&cols.legend(r));

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
        cols.tables(
            &mut s,
            &["kernel"],
            &labels,
            |l| vec![l.clone()],
            |l, b| {
                let section = if l == "render" { "frame" } else { "kernel" };
                r.get(section, b, n, l, None).map(|x| ms(x.median_ns)).unwrap_or_else(|| "–".into())
            },
        );
        let samples = r.get("kernel", &backends[0], n, SUBSTEP, None).map(|x| x.samples).unwrap_or(0);
        let _ = writeln!(s, "Samples per kernel: {samples} substeps.\n");
        let searches: Vec<String> = r
            .searches
            .iter()
            .filter(|c| c.n as u64 == n)
            .map(|c| format!("{} {:.2} (+ {:.2} partial)", c.backend, c.per_frame[0], c.per_frame[1]))
            .collect();
        if !searches.is_empty() {
            let _ = writeln!(
                s,
                "The contact between triangles' searches for pairs a frame of {} substeps (the `tri_bounds` row is the substep's start with them): {}.\n",
                r.settings.substeps,
                searches.join(", ")
            );
        }
    }

    let _ = writeln!(s, "## Time per frame and frames per second against grid size (Figures 7.5–7.8)\n");
    let _ = writeln!(s, "![frame time](frame_time.png) ![frames per second](fps.png)\n");
    let _ = writeln!(
        s,
        "Milliseconds per frame ({} substeps + offscreen render), frames per second in brackets.\n",
        st.substeps
    );
    cols.tables(
        &mut s,
        &["n", "particles"],
        &sizes,
        |n| vec![n.to_string(), (n * n).to_string()],
        |&n, b| {
            r.get("frame", b, n, "frame", None)
                .map(|x| format!("{} ({:.1})", ms(x.median_ns), 1e9 / x.median_ns))
                .unwrap_or_else(|| "–".into())
        },
    );
    let _ = writeln!(s, "ns per particle-substep (GPU substep time, or the CPU solvers' wall time):\n");
    cols.tables(
        &mut s,
        &["n"],
        &sizes,
        |n| vec![n.to_string()],
        |&n, b| {
            r.get("kernel", b, n, SUBSTEP, None)
                .map(|x| format!("{:.1}", x.median_ns / (n * n) as f64))
                .unwrap_or_else(|| "–".into())
        },
    );

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
            let _ = writeln!(
                s,
                "| {} | {} | {} | {:.0} % |",
                cols.name(&x.backend),
                x.n,
                runs.join(" / "),
                x.spread() * 100.0
            );
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
            cols.name(&c.backend),
            c.n,
            cols.name(&c.reference),
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
    clothlab::files::write_bytes(&p, bytes)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::results::{Cell, test_results};
    use clothlab::core::TimingRow;
    use clothlab::core::timing::OverheadRow;

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
            searches: None,
        }
    }

    fn results(cells: Vec<Cell>, overhead: Vec<(String, String, Vec<OverheadRow>)>) -> Results {
        test_results(cells, overhead, vec![])
    }

    #[test]
    fn the_report_gives_the_contacts_searches_a_frame() {
        // A cell with the contact between triangles names its searches a frame (the
        // counts as the cell measured them, two decimals); one without it adds nothing.
        let mut c = cell("cpu", 64, 1e5, 0.0);
        c.searches = Some([1.5, 2.25]);
        let rep = report(&results(vec![c], vec![]));
        assert!(rep.contains("cpu 1.50 (+ 2.25 partial)"), "{rep}");
        let rep = report(&results(vec![cell("cpu", 64, 1e5, 0.0)], vec![]));
        assert!(!rep.contains("searches for pairs"), "{rep}");
    }

    #[test]
    fn a_backend_that_ends_elsewhere_fails_the_same_workload_check() {
        // (3 + 2·10) frames × 16 substeps × 5e-5 m = 18.4 mm allowed.
        let r = results(
            vec![cell("cpu", 64, 1e5, 0.0), cell("wgpu", 64, 1e4, 0.001), cell("vulkan", 64, 1e4, 0.05)],
            vec![],
        );
        let by = |b: &str| r.checks.iter().find(|c| c.backend == b).unwrap();
        assert!((by("wgpu").bound_m - 1.84e-2).abs() < 1e-9);
        assert!(by("wgpu").ok && (by("wgpu").max_dev_m - 1e-3).abs() < 1e-6, "{:?}", by("wgpu"));
        assert!(!by("vulkan").ok, "5 cm off must fail: {:?}", by("vulkan"));
        assert!(report(&r).contains("**FAILED**"));
        // A NaN position is never within the bound.
        let mut bad = cell("cpu-par", 64, 1e5, 0.0);
        bad.probe[3][1] = f32::NAN;
        let r = results(vec![cell("cpu", 64, 1e5, 0.0), bad], vec![]);
        assert!(!r.checks[0].ok);
    }

    #[test]
    fn the_report_names_the_scene_it_measured() {
        // It said "default scene" whatever --scene gave; results.json of earlier runs (no
        // field) read back as the default scene they measured.
        let mut r = results(vec![cell("cpu", 64, 1e5, 0.0)], vec![]);
        assert!(report(&r).contains("| workload | default scene, 16 substeps"));
        r.settings.scene = "A cloth on a spinning sphere (scenes/spinning-sphere.toml)".into();
        assert!(report(&r).contains("| workload | A cloth on a spinning sphere (scenes/spinning-sphere.toml), 16"));
        let mut json = serde_json::to_value(&r).unwrap();
        json["settings"].as_object_mut().unwrap().remove("scene");
        let old: Results = serde_json::from_value(json).unwrap();
        assert_eq!(old.settings.scene, "default scene");
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
