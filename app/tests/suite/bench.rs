//! `clothlab bench`: a small run writes every file, well-formed, with sane numbers; bad
//! input is refused; cells over the time budget are skipped and said so; a stopped run
//! keeps its cells and `--resume` completes it; an interrupted run leaves old outputs.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::{clothlab, gpu_required};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("clothlab-bench-{name}-{}", std::process::id()));
    std::fs::remove_dir_all(&d).ok();
    d
}

/// Splits one CSV line, honouring double quotes (the writer quotes fields with commas).
fn split_csv(line: &str) -> Vec<String> {
    let (mut out, mut cur, mut quoted) = (Vec::new(), String::new(), false);
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => out.push(std::mem::take(&mut cur)),
            _ => cur.push(c),
        }
    }
    out.push(cur);
    out
}

/// Decodes a PNG and checks it is a real picture: the expected size and more than a
/// handful of colours (axes, text, lines).
fn check_png(path: &Path) {
    let img = image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb8();
    assert!(img.width() >= 600 && img.height() >= 400, "{}: {}×{}", path.display(), img.width(), img.height());
    let mut colours: Vec<[u8; 3]> = img.pixels().map(|p| p.0).collect();
    colours.sort_unstable();
    colours.dedup();
    // White background, black text, grey grid, a colour per series, anti-aliased edges.
    assert!(colours.len() > 20, "{}: only {} colours — nothing drawn?", path.display(), colours.len());
    // A chart on a white background: these plots measured 78–89 % white (2026-11-22).
    // Above 99.5 % nothing was drawn; below 30 % something filled the canvas. The wide
    // band leaves room for other data (more backends, longer bars).
    let white = img.pixels().filter(|p| p.0 == [255, 255, 255]).count() as f64 / (img.width() * img.height()) as f64;
    eprintln!("{}: {:.1}% white, {} colours", path.display(), white * 100.0, colours.len());
    assert!((0.3..0.995).contains(&white), "{}: {:.1}% white", path.display(), white * 100.0);
}

#[test]
fn a_small_run_writes_every_file_with_positive_finite_numbers() {
    let out = tmp("small");
    // The frame measurement renders offscreen: at 160 × 120 instead of 1280 × 720 a frame
    // costs llvmpipe a few ms instead of ~250 (what is checked is that the numbers are
    // there, positive and finite, not their size).
    let o = clothlab(&[
        "bench",
        "--sizes",
        "16,32",
        "--iters",
        "5",
        "--resolution",
        "160x120",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "bench failed: {err}");
    assert!(!err.contains("panicked"), "{err}");
    let gpu = !err.contains("no wgpu adapter");
    assert!(gpu || !gpu_required(), "CI has lavapipe, but: {err}");

    // CSV: the header, 11 fields a row, numbers positive and finite, min ≤ median ≤ max.
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let mut lines = csv.lines();
    let header = split_csv(lines.next().unwrap());
    assert_eq!(header.join(","), "section,backend,size,label,clock,samples,median_ns,min_ns,max_ns,adapter,machine");
    let rows: Vec<Vec<String>> = lines.map(split_csv).collect();
    // The gl backend's cells carry the name of the variant it runs: `optimized` fitted to
    // the context (on llvmpipe `gl-optimized+constants=uniform+neighbours=load`: no push
    // constants, no subgroups), so its name is taken from the rows.
    let gl = rows.iter().map(|r| r[1].as_str()).find(|b| *b == "gl" || b.starts_with("gl-optimized"));
    let backends: Vec<&str> = if gpu {
        let gl = gl.expect("a gl cell");
        vec!["cpu", "cpu-par", "wgpu-naive", "wgpu", "vulkan-naive", "vulkan", "gl-naive", gl]
    } else {
        vec!["cpu", "cpu-par"]
    };
    for r in &rows {
        assert_eq!(r.len(), 11, "{r:?}");
        let samples: usize = r[5].parse().unwrap();
        let [med, min, max] = [6, 7, 8].map(|i| r[i].parse::<f64>().unwrap());
        assert!(samples >= 1, "{r:?}");
        for v in [med, min, max] {
            assert!(v.is_finite() && v > 0.0, "{r:?}");
        }
        assert!(min <= med && med <= max, "{r:?}");
        assert!(!r[10].is_empty() && !r[9].is_empty(), "machine and adapter in every row: {r:?}");
    }
    let find = |section: &str, backend: &str, size: &str, label: &str| {
        rows.iter().find(|r| r[0] == section && r[1] == backend && r[2] == size && r[3] == label)
    };
    for &b in &backends {
        for n in ["16", "32"] {
            // --iters 5 rounds up to one frame of 16 substeps: 16 samples per kernel.
            let sub = find("kernel", b, n, "substep").unwrap_or_else(|| panic!("no substep row for {b} n={n}"));
            assert_eq!(sub[5], "16", "{sub:?}");
            let frame = find("frame", b, n, "frame").unwrap_or_else(|| panic!("no frame row for {b} n={n}"));
            assert_eq!(frame[5], "1", "{frame:?}");
        }
    }
    if gpu {
        // Four stacks: wgpu on its preferred backend (Vulkan on lavapipe), wgpu on GL,
        // raw Vulkan, raw GL.
        for api in ["wgpu", "wgpu-gl", "vulkan", "gl"] {
            for k in ["1", "64"] {
                assert!(rows.iter().any(|r| r[0] == "overhead"
                    && r[1] == api
                    && r[3] == "chain"
                    && r[2] == k
                    && r[4] == "gpu"));
            }
            assert!(find("overhead", api, "0", "empty submit").is_some());
            assert!(find("overhead", api, "16777216", "readback").is_some());
        }
    }

    // JSON: the same rows, the machine, and every same-workload check passed.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    assert_eq!(json["rows"].as_array().unwrap().len(), rows.len());
    assert!(!json["machine"].as_str().unwrap().is_empty());
    assert_eq!(json["settings"]["frames"], 1);
    let checks = json["checks"].as_array().unwrap();
    assert_eq!(checks.len(), 2 * (backends.len() - 1), "every backend but the reference, at each size");
    for c in checks {
        assert_eq!(c["ok"], true, "{c}");
        assert!(c["max_dev_m"].as_f64().unwrap() <= c["bound_m"].as_f64().unwrap());
    }

    // Report and plots.
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    for key in ["## Per-kernel time at 32×32", "## Time per frame", "## Targets", "## Same workload", "kernels.png"] {
        assert!(report.contains(key), "report.md lacks `{key}`");
    }
    for b in &backends {
        assert!(report.contains(&format!("| {b} ")), "report.md lacks {b}");
    }
    let mut plots = vec!["kernels", "frame_time", "fps"];
    if gpu {
        plots.push("overhead");
        assert!(report.contains("## API overhead"));
    }
    for p in plots {
        check_png(&out.join(format!("{p}.png")));
        let svg = std::fs::read_to_string(out.join(format!("{p}.svg"))).unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"), "{p}.svg is not an SVG document");
        let series = if p == "overhead" { "vulkan chain gpu" } else { "cpu-par" };
        assert!(svg.contains(series), "{p}.svg has no series `{series}`");
    }

    // --replot rebuilds the report and plots from results.json alone.
    std::fs::remove_file(out.join("report.md")).unwrap();
    std::fs::remove_file(out.join("kernels.png")).unwrap();
    let o = clothlab(&["bench", "--replot", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(std::fs::read_to_string(out.join("report.md")).unwrap(), report, "the same report from the JSON");
    check_png(&out.join("kernels.png"));
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn a_cell_over_the_budget_is_skipped_and_reported() {
    let out = tmp("budget");
    // The 8×8 cell takes well over a microsecond, so 512×512 (4096× the particles) is
    // predicted over a 1 ms budget and skipped.
    let o = clothlab(&[
        "bench",
        "--backends",
        "cpu",
        "--sizes",
        "8,512",
        "--iters",
        "1",
        "--cell-budget",
        "0.001",
        "--no-overhead",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("cpu at n=512: skipped"), "{err}");
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("## Skipped") && report.contains("cpu at n=512: skipped"), "{report}");
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    assert!(csv.contains(",cpu,8,substep,") && !csv.contains(",cpu,512,"), "{csv}");
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn the_ladder_climbs_one_switch_at_a_time_and_plots_what_each_buys() {
    let out = tmp("ladder");
    let o = clothlab(&[
        "bench",
        "--ladder",
        // One API: the ladder's table, bounds and plot are the bench's, whatever the API
        // (each API's rungs are held to the CPU's bits in the cross-backend suite); every
        // rung is pipelines for llvmpipe to compile, so a second API doubled this test
        // (153 s on a cold shader cache, the app suite's longest by ten times).
        "--backends",
        "vulkan",
        "--sizes",
        "16",
        "--iters",
        "16",
        // A small render target (a rung's frame: 29 → 17 s for the whole ladder on lavapipe).
        "--resolution",
        "160x120",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    if err.contains("no wgpu adapter") && !gpu_required() {
        return;
    }
    assert!(o.status.success(), "{err}");
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    // Every figure the report shows was written beside it.
    let figures: Vec<&str> = report.split("](").skip(1).filter_map(|s| s.split(')').next()).collect();
    assert!(figures.iter().any(|f| f.starts_with("ladder_")) && figures.contains(&"kernels.png"), "{figures:?}");
    for f in figures.iter().filter(|f| f.ends_with(".png")) {
        assert!(out.join(f).is_file(), "the report shows {f}, which the bench did not write");
    }
    {
        let api = "vulkan";
        let table: Vec<&str> = report
            .split(&format!("### {api}, n = 16"))
            .nth(1)
            .unwrap_or_else(|| panic!("no {api} ladder in {report}"))
            .lines()
            .take_while(|l| !l.starts_with("Fastest"))
            .filter(|l| l.starts_with("| ") && !l.starts_with("| rung"))
            .collect();
        // naive, the rungs of the ladder, the thesis preset.
        let rows = clothlab::engine::variant::LADDER.len() + 2;
        assert_eq!(table.len(), rows, "{api}: {table:#?}");
        assert!(table[0].starts_with("| naive | ") && table[0].contains("| 1.00× |"), "{}", table[0]);
        assert!(table[rows - 1].starts_with("| **thesis (preset)** |"), "{}", table[rows - 1]);
        // Every measured rung names its bound with the numbers that decided it.
        for row in table.iter().filter(|r| !r.contains("skipped")) {
            assert!(
                ["dispatch overhead (", "submission / CPU (", "memory (", "arithmetic / latency ("]
                    .iter()
                    .any(|b| row.contains(b)),
                "{row}"
            );
        }
        check_png(&out.join(format!("ladder_{api}_16.png")));
    }
    // A rung the adapter lacks is skipped saying which switch (lavapipe has them all).
    for row in report.lines().filter(|l| l.contains("skipped:")) {
        assert!(row.contains("skipped: switch "), "{row}");
    }
    assert!(report.contains("The thesis preset draws"), "{report}");
    // The same report from the JSON.
    let o = clothlab(&["bench", "--replot", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(std::fs::read_to_string(out.join("report.md")).unwrap(), report);
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn bad_bench_input_is_refused_in_one_line() {
    for (args, expect) in [
        (&["bench", "--sizes", "1"][..], "grid sizes must be in 2 ..= 4096"),
        (&["bench", "--sizes", "16,5000"], "grid sizes must be in 2 ..= 4096"),
        (&["bench", "--iters", "0"], "invalid --iters 0"),
        (&["bench", "--resolution", "10x10"], "width and height must be in 16 ..= 8192"),
        (&["bench", "--resolution", "wide"], "expected WIDTHxHEIGHT"),
        (&["bench", "--cell-budget", "0"], "invalid --cell-budget"),
        (&["bench", "--repeat", "0"], "invalid --repeat 0"),
        (&["bench", "--backends", "cuda"], "invalid value 'cuda'"),
        (&["bench", "--sizes", "8", "--out", "/proc/clothlab-bench"], "cannot create /proc/clothlab-bench"),
        (&["bench", "--replot", "--out", "/nonexistent-dir"], "cannot read /nonexistent-dir/results.json"),
        (&["bench", "--ladder", "--backends", "cpu,cpu-par", "--sizes", "8"], "name at least one GPU backend"),
        (&["bench", "--backends", "cpu", "--sizes", "8", "--resume", "/nonexistent-dir"], "no cells.jsonl there"),
        (&["bench", "--resume", "/tmp/a", "--out", "/tmp/b"], "--resume /tmp/a writes there: leave out --out /tmp/b"),
        (&["bench", "--integrators", "--resume", "/tmp/a"], "cannot be used with"),
        (&["bench", "--mesh-vs-grid", "--ladder"], "cannot be used with"),
        (&["bench", "--envs", "0", "--sizes", "4"], "invalid --envs 0"),
        (&["bench", "--envs", "4", "--ladder"], "cannot be used with"),
        (&["bench", "--irregular", "../scenes/meshes/fan.obj"], "--mesh-vs-grid"),
        (
            &["bench", "--mesh-vs-grid", "--backends", "cpu", "--sizes", "8", "--irregular", "../scenes/mesh-fan.toml"],
            "--irregular: ../scenes/mesh-fan.toml",
        ),
        (
            &[
                "bench",
                "--mesh-vs-grid",
                "--backends",
                "cpu",
                "--sizes",
                "8",
                "--scene",
                "../scenes/mesh-flag.toml",
                "--out",
                "/tmp/clothlab-mesh-vs-grid-refused",
            ],
            "the scene's cloth is a mesh already",
        ),
        (
            &["bench", "--backends", "vulkan", "--variant", "turbo", "--sizes", "8"],
            "the presets are naive, optimized, thesis",
        ),
    ] {
        let o = clothlab(args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} should fail");
        assert!(err.contains(expect), "{args:?}: expected `{expect}` in: {err}");
        assert!(!err.contains("panicked") && !err.contains("backtrace"), "{args:?}: {err}");
    }
}

/// Sends `signal` (`INT`, `TERM`) to `pid`.
fn signal(pid: u32, signal: &str) {
    let ok = Command::new("kill").args([&format!("-{signal}"), &pid.to_string()]).status().expect("run kill");
    assert!(ok.success(), "kill -{signal} {pid}");
}

/// Lines of `dir`/cells.jsonl that record a measured cell.
fn journal_cells(dir: &Path) -> Vec<String> {
    std::fs::read_to_string(dir.join("cells.jsonl"))
        .unwrap_or_default()
        .lines()
        .filter(|l| l.starts_with("{\"cell\""))
        .map(str::to_owned)
        .collect()
}

#[cfg(unix)]
#[test]
fn a_stopped_bench_keeps_its_cells_and_resume_measures_only_the_rest() {
    let out = tmp("resume");
    let dir = out.to_str().unwrap();
    // 2 backends × 2 sizes × 2 rounds = 8 cells of 0.3–1 s each on the 2-core dev VM:
    // time to stop it between its first and its last.
    let plan = ["bench", "--backends", "cpu,cpu-par", "--sizes", "64,96", "--iters", "160", "--repeat", "2"];
    let mut args = plan.to_vec();
    args.extend(["--no-overhead", "--resolution", "64x64", "--out", dir]);
    let child =
        Command::new(env!("CARGO_BIN_EXE_clothlab")).args(&args).stderr(std::process::Stdio::piped()).spawn().unwrap();
    // Stop it once its first cell is in the journal (the plan is the first line).
    let t0 = std::time::Instant::now();
    while journal_cells(&out).is_empty() {
        assert!(t0.elapsed().as_secs() < 120, "no cell measured in two minutes");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    signal(child.id(), "INT");
    let stopped = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&stopped.stderr);
    assert_eq!(stopped.status.code(), Some(130), "a stopped bench exits 130: {err}");
    let kept = journal_cells(&out);
    assert!((1..8).contains(&kept.len()), "{} of 8 cells kept", kept.len());
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    let said = format!("**Interrupted after {} of 8 cells**", kept.len());
    assert!(report.contains(&said), "the report says `{said}`: {report}");
    assert!(err.contains("--resume"), "{err}");

    // A fresh run in that folder would lose the stopped one's cells: refused, naming
    // --resume, and nothing changes.
    let o = clothlab(&args);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("holds a stopped run's") && e.contains("--resume"), "{e}");
    assert_eq!(journal_cells(&out), kept);

    // Another plan is refused in one line, naming what differs, and changes nothing.
    let mut other = args.clone();
    other[4] = "64,128";
    let last = other.len() - 2;
    other[last] = "--resume";
    let o = clothlab(&other);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("sizes: [64,96] there, [64,128] here"), "{e}");
    assert_eq!(e.trim_end().lines().count(), 1, "one line: {e}");
    assert_eq!(journal_cells(&out), kept);

    // The same plan measures what is missing: every cell exactly once.
    let mut again = args.clone();
    again[last] = "--resume";
    let o = clothlab(&again);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let all = journal_cells(&out);
    assert_eq!(all.len(), 8, "8 cells in all");
    assert_eq!(all[..kept.len()], kept[..], "the kept cells are not measured again");
    let mut keys: Vec<String> = all.iter().map(|l| l.split(",\"cell\":").next().unwrap().to_owned()).collect();
    keys.sort();
    keys.dedup();
    assert_eq!(keys.len(), 8, "each (size, job, round) once: {keys:?}");
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(!report.contains("Interrupted"));
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    for (b, n) in [("cpu", 64), ("cpu-par", 64), ("cpu", 96), ("cpu-par", 96)] {
        let rows = csv.lines().filter(|l| l.starts_with(&format!("kernel,{b},{n},substep,"))).count();
        assert_eq!(rows, 1, "{b} at n = {n}: one substep row");
    }
    // A finished run's journal is replaced by the next run without a word.
    let mut small = args.clone();
    small[4] = "64";
    let o = clothlab(&small);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(journal_cells(&out).len(), 4, "a new journal: 2 backends × 1 size × 2 rounds");
    std::fs::remove_dir_all(&out).ok();
}

#[cfg(target_os = "linux")]
#[test]
fn an_interrupted_sim_leaves_the_old_output_as_it_was() {
    let out = tmp("sim-out");
    std::fs::create_dir_all(&out).unwrap();
    let path = out.join("state.json");
    std::fs::write(&path, "the old results").unwrap();
    let child = Command::new(env!("CARGO_BIN_EXE_clothlab"))
        .args(["sim", "--backend", "cpu", "--n", "128", "--steps", "10000000", "--out", path.to_str().unwrap()])
        // Without XDG_RUNTIME_DIR clothlab runs itself again without Mesa's device-select
        // layer: by exec, in this very process, so the signal below reaches the simulation.
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("NODEVICE_SELECT")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Long enough to be simulating (the output is checked before the first substep).
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let environ = std::fs::read(format!("/proc/{}/environ", child.id())).unwrap_or_default();
    assert!(
        environ.split(|&b| b == 0).any(|v| v == b"NODEVICE_SELECT=1"),
        "the re-run without the device-select layer is the process that was started, not a child of it"
    );
    signal(child.id(), "INT");
    let status = child.wait_with_output().unwrap().status;
    assert!(!status.success(), "stopped, not finished");
    assert_eq!(std::fs::read_to_string(&path).unwrap(), "the old results");
    let names: Vec<_> = std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(names.len(), 1, "nothing else left beside it: {names:?}");
    std::fs::remove_dir_all(&out).ok();
}

/// `--mesh-vs-grid`: the grid, the grid kernel by kernel and the grid as a mesh on a CPU
/// backend; the grid, the grid without its grid-only switches and the grid as a mesh on an
/// optimized GPU backend; an irregular mesh (the fan, 513 particles) on both; every time
/// positive and finite; the files written.
#[test]
fn mesh_vs_grid_measures_the_grid_and_the_same_grid_as_a_mesh() {
    let out = tmp("mesh-vs-grid");
    let args = [
        "bench",
        "--mesh-vs-grid",
        "--sizes",
        "12",
        "--iters",
        "16",
        "--backends",
        "cpu,wgpu",
        "--irregular",
        "../scenes/meshes/fan.obj",
        "--out",
    ];
    let o = clothlab(&[&args[..], &[out.to_str().unwrap()]].concat());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "bench failed: {err}");
    let csv = std::fs::read_to_string(out.join("mesh-vs-grid.csv")).unwrap();
    let rows: Vec<Vec<String>> = csv.lines().skip(1).map(split_csv).collect();
    let cloths: Vec<(&str, &str)> = rows.iter().map(|r| (r[1].as_str(), r[2].as_str())).collect();
    for want in [("cpu", "grid"), ("cpu", "grid, kernel by kernel"), ("cpu", "grid as mesh"), ("cpu", "irregular mesh")]
    {
        assert!(cloths.contains(&want), "no {want:?} in {cloths:?}");
    }
    for r in &rows {
        let particles: usize = r[3].parse().unwrap();
        assert_eq!(particles, if r[2] == "irregular mesh" { 513 } else { 144 }, "{r:?}");
        let ns: f64 = r[4].parse().unwrap();
        assert!(ns.is_finite() && ns > 0.0, "{r:?}");
    }
    let md = std::fs::read_to_string(out.join("mesh-vs-grid.md")).unwrap();
    if cloths.contains(&("wgpu", "grid")) {
        for want in [("wgpu", "grid, from the table"), ("wgpu", "grid as mesh"), ("wgpu", "irregular mesh")] {
            assert!(cloths.contains(&want), "no {want:?} in {cloths:?}");
        }
        assert!(md.contains("| wgpu | grid as mesh |") && !md.contains("Not measured"), "{md}");
    } else {
        assert!(!gpu_required(), "CI has lavapipe, but: {err}");
    }
    assert!(std::fs::metadata(out.join("mesh-vs-grid.png")).unwrap().len() > 1000);
    std::fs::remove_dir_all(&out).ok();
}

/// `--envs`: a batch and the same worlds as separate simulations on the CPU backends and
/// a GPU API's two recipes (the naive one's scatters too), at every count of worlds, each
/// time positive and finite; the files written.
#[test]
fn worlds_measure_a_batch_against_separate_simulations() {
    let out = tmp("worlds");
    let args = [
        "bench",
        "--envs",
        "1,3",
        "--sizes",
        "6",
        "--iters",
        "8",
        "--backends",
        "cpu,cpu-par,vulkan,vulkan-naive",
        "--out",
    ];
    let o = clothlab(&[&args[..], &[out.to_str().unwrap()]].concat());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "bench failed: {err}");
    let csv = std::fs::read_to_string(out.join("worlds.csv")).unwrap();
    let rows: Vec<Vec<String>> = csv.lines().skip(1).map(split_csv).collect();
    let cells: Vec<(&str, &str)> = rows.iter().map(|r| (r[1].as_str(), r[2].as_str())).collect();
    assert_eq!(
        cells,
        [
            ("cpu", "1"),
            ("cpu", "3"),
            ("cpu-par", "1"),
            ("cpu-par", "3"),
            ("vulkan", "1"),
            ("vulkan", "3"),
            ("vulkan-naive", "1"),
            ("vulkan-naive", "3")
        ]
    );
    for r in &rows {
        for v in [&r[3], &r[5]] {
            let us: f64 = v.parse().unwrap();
            assert!(us.is_finite() && us > 0.0, "{r:?}");
        }
    }
    let md = std::fs::read_to_string(out.join("worlds.md")).unwrap();
    assert!(!md.contains("no world dimension"), "{md}");
    check_png(&out.join("worlds.png"));
    std::fs::remove_dir_all(&out).ok();
}

/// The main bench on a scene of several cloths (one mesh to the solvers, `n = 0`): it runs
/// on a CPU and a GPU backend and checks they simulated the same workload (its probe of a
/// mesh's particles read index `n - 1` of a grid before, and panicked on a mesh).
#[test]
fn bench_runs_a_scene_of_several_cloths() {
    let out = tmp("bench-two-cloths");
    let args = ["bench", "--scene", "../scenes/two-cloths.toml", "--sizes", "8", "--iters", "16", "--no-overhead"];
    let o = clothlab(&[&args[..], &["--backends", "cpu-par,wgpu", "--out", out.to_str().unwrap()]].concat());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "bench failed: {err}");
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    assert!(csv.lines().any(|l| l.contains("cpu-par")), "{csv}");
    assert!(!err.contains("panicked"), "{err}");
    std::fs::remove_dir_all(&out).ok();
}
