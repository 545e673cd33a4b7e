//! `clothlab bench --mesh-vs-grid`: what the grid's regularity buys.
//!
//! The scene's n × n cloth runs twice on each backend: as the grid, and loaded as a mesh
//! (`core::mesh::grid_mesh`: the same vertices in the same order, the same triangles and
//! the same two pins; its springs are the mesh's — edges and springs across edges — and its
//! rim vertices lighter, so the work per particle is comparable, not equal: 12 slots each
//! away from the border either way). On the CPU backends a third cloth isolates the fused
//! sweep: the grid kernel by kernel (`CLOTHLAB_CPU_FUSED=off`'s path), which is what a mesh
//! runs. On an optimized GPU backend a third cloth does the same for the GPU's grid-only
//! switches: the grid with `table=storage,neighbours=load` (what a mesh falls back to: no
//! neighbours by offset, no constants in a uniform block, no shuffles), so that the mesh's
//! cost splits into what those switches buy and what the mesh's own springs and tables
//! cost. A backend that cannot run a cloth gets a note with its one-line refusal. Every
//! cell is rebuilt and timed each round, rounds interleaved; the report gives the median of
//! the rounds' median frame times per particle-substep and the rounds' spread.

use std::fmt::Write as _;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Result;
use clothlab::core::{Scene, SimParams};
use clothlab::cpu::{CpuSolver, Exec};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::plot::{FONT, Figure, both, err};
use super::{Request, WARMUP_FRAMES, all_backends, cpu_label, make_out_dir};
use crate::cli::BenchArgs;
use crate::out::outln;
use clothlab::backend::{AnySolver, Backend, GpuSetup, Shared, make};
use clothlab::engine::VariantSpec;
use clothlab::engine::variant::{Neighbours, Table};

/// The backends measured unless `--backends` says otherwise: the CPU ones and each GPU
/// API's optimized one (the naive recipes have no grid-only switch to compare).
pub const DEFAULT_BACKENDS: [Backend; 5] = [Backend::Cpu, Backend::CpuPar, Backend::Wgpu, Backend::Vulkan, Backend::Gl];

/// The cloths a backend runs.
pub const GRID: &str = "grid";
/// The grid on the CPU's kernel-by-kernel path.
pub const GRID_KERNELS: &str = "grid, kernel by kernel";
/// The grid on a GPU without its grid-only switches (the table from storage, neighbours
/// loaded).
pub const GRID_TABLE: &str = "grid, from the table";
/// The grid loaded as a mesh.
pub const MESH: &str = "grid as mesh";
/// A mesh of another triangulation (`--irregular FILE`).
pub const IRREGULAR: &str = "irregular mesh";

/// One cell: a cloth on a backend at a size.
#[derive(Debug, Clone)]
pub struct Row {
    /// Particles per side.
    pub n: u32,
    /// Backend name.
    pub backend: String,
    /// [`GRID`], [`GRID_KERNELS`], [`GRID_TABLE`] or [`MESH`].
    pub cloth: &'static str,
    /// Its particles (n² but for an irregular mesh).
    pub particles: usize,
    /// Median over rounds of the median frame time per particle-substep, ns.
    pub ns: f64,
    /// (largest − smallest) / median of the rounds' values.
    pub spread: f64,
}

/// The scene with its cloth the mesh of `file` (`--irregular`), its centre where the grid's
/// top edge is, unpinned; refused in one line if the file cannot be a cloth or the
/// scene's parameters cannot simulate it.
pub fn irregular(base: &Scene, file: &std::path::Path) -> Result<Scene> {
    use clothlab::core::mesh::{PlacedMesh, Placement};
    let placement = Placement { translate: base.cloth.top_center, ..Placement::default() };
    let placed = PlacedMesh::load(file, None, &placement).map_err(|e| anyhow::anyhow!("--irregular: {e}"))?;
    let mut scene = base.clone();
    scene.cloth.mesh = Some(file.to_path_buf());
    scene.cloth.pinning = clothlab::core::Pinning::None;
    scene.cloth.translate = placement.translate;
    scene.cloth.mesh_data = Some(std::sync::Arc::new(placed));
    Ok(scene)
}

/// The scene's grid at side `n` as a mesh (`core::cloth::grid_as_mesh`).
pub fn as_mesh(grid: &Scene) -> Result<Scene> {
    clothlab::core::cloth::grid_as_mesh(grid)
        .map_err(|e| anyhow::anyhow!("--mesh-vs-grid compares the scene's grid with itself as a mesh: {e}"))
}

/// The median frame time of `frames` frames after the warm-up, ns: each frame waited for
/// (`AnySolver::finish`, as the main bench's frame table waits: with kernel timing off, GL
/// returns from a frame before the GPU has run it — on an H100 the GL cells measured
/// submission alone, 2026-11-25).
fn time(solver: &mut AnySolver, frames: u32) -> Result<f64> {
    solver.get().set_kernel_timing(false);
    for _ in 0..WARMUP_FRAMES {
        solver.get().step_frame()?;
        solver.finish()?;
    }
    let mut t = Vec::with_capacity(frames as usize);
    for _ in 0..frames {
        let t0 = Instant::now();
        solver.get().step_frame()?;
        solver.finish()?;
        t.push(t0.elapsed().as_nanos() as f64);
    }
    t.sort_by(f64::total_cmp);
    Ok(t[t.len() / 2])
}

/// One cell's solver, or why the backend cannot run it.
fn solver(
    backend: Backend,
    cloth: &str,
    grid: &Scene,
    mesh: &Scene,
    irregular: Option<&Scene>,
    params: &SimParams,
) -> Result<AnySolver> {
    let cpu = match backend {
        Backend::Cpu => Some(Exec::Serial),
        Backend::CpuPar => Some(Exec::Parallel),
        _ => None,
    };
    let scene = match (cloth, irregular) {
        (MESH, _) => mesh,
        (IRREGULAR, Some(s)) => s,
        _ => grid,
    };
    if let Some(exec) = cpu {
        let mut s = CpuSolver::new(exec, scene.clone(), params.clone())?;
        s.fused = cloth == GRID;
        return Ok(AnySolver::Cpu(Box::new(s)));
    }
    let mut setup = GpuSetup::default();
    if cloth == GRID_TABLE {
        let preset = backend.preset().unwrap_or("optimized");
        let set = ["table=storage".to_string(), "neighbours=load".to_string()];
        setup.variant = Some(VariantSpec::parse(preset, &set)?);
    }
    make(backend, scene.clone(), params.clone(), &setup, &Shared::None)
}

/// The cloths `backend` runs: on the CPU the grid kernel by kernel too, on a GPU backend
/// whose preset uses a grid-only switch the grid without them too.
fn cloths_of(backend: Backend) -> &'static [&'static str] {
    match backend {
        Backend::Cpu | Backend::CpuPar => &[GRID, GRID_KERNELS, MESH],
        b if b.variant().table == Table::Uniform || b.variant().neighbours == Neighbours::Shuffle => {
            &[GRID, GRID_TABLE, MESH]
        }
        _ => &[GRID, MESH],
    }
}

/// Measures every cell `repeat` times, interleaved; the rows and the notes (refusals).
pub fn measure(
    base: &Scene,
    params: &SimParams,
    irregular: Option<&Scene>,
    backends: &[Backend],
    sizes: &[u32],
    frames: u32,
    repeat: u32,
) -> Result<(Vec<Row>, Vec<String>)> {
    let mut rows = Vec::new();
    let mut notes = Vec::new();
    for &n in sizes {
        let mut grid = base.clone();
        grid.cloth.n = n;
        let mesh = as_mesh(&grid)?;
        let mut cells: Vec<(Backend, &'static str)> = Vec::new();
        for &b in backends {
            for &c in cloths_of(b).iter().chain(irregular.map(|_| &IRREGULAR)) {
                match solver(b, c, &grid, &mesh, irregular, params) {
                    Ok(_) => cells.push((b, c)),
                    Err(e) => notes.push(format!("n = {n}: {c} on {}: {e:#}", b.name())),
                }
            }
        }
        let mut values = vec![Vec::new(); cells.len()];
        let mut particles = vec![0; cells.len()];
        for round in 0..repeat {
            for (k, &(b, c)) in cells.iter().enumerate() {
                let mut s = solver(b, c, &grid, &mesh, irregular, params)?;
                particles[k] = s.get().state()?.pos.len();
                let np = particles[k] as f64;
                let ns = time(&mut s, frames)? / params.substeps as f64 / np;
                eprintln!("n = {n} round {round}: {:8} {c:24} {ns:9.1} ns per particle-substep", b.name());
                values[k].push(ns);
            }
        }
        for (((b, c), mut v), particles) in cells.into_iter().zip(values).zip(particles) {
            v.sort_by(f64::total_cmp);
            let median = v[v.len() / 2];
            let spread = (v[v.len() - 1] - v[0]) / median;
            rows.push(Row { n, backend: b.name().into(), cloth: c, particles, ns: median, spread });
        }
    }
    Ok((rows, notes))
}

/// The grid's time on the same backend and size as `r`.
fn grid_of<'a>(rows: &'a [Row], r: &Row) -> Option<&'a Row> {
    rows.iter().find(|g| g.n == r.n && g.backend == r.backend && g.cloth == GRID)
}

/// The report: a table per size, the ratios to the grid, the notes.
pub fn report(rows: &[Row], notes: &[String], machine: &str, repeat: u32) -> String {
    let mut s = String::from("# The grid against the same grid loaded as a mesh\n\n");
    let _ = writeln!(
        s,
        "{machine}; {repeat} interleaved round(s) per cell, each the median frame time after {WARMUP_FRAMES} warm-up frames. \
         ns per particle-substep (wall time, the GPU waited for); `× grid` is the cell over the grid on the same backend.\n"
    );
    let mut sizes: Vec<u32> = rows.iter().map(|r| r.n).collect();
    sizes.dedup();
    for n in sizes {
        let _ = writeln!(s, "## n = {n} ({} particles)\n", n * n);
        let _ = writeln!(s, "| backend | cloth | ns/particle-substep | × grid | spread |\n|---|---|---:|---:|---:|");
        for r in rows.iter().filter(|r| r.n == n) {
            let ratio = grid_of(rows, r).map(|g| format!("{:.2}", r.ns / g.ns)).unwrap_or_default();
            // Three significant digits: a real GPU's cells are fractions of a nanosecond.
            let ns = if r.ns < 10.0 { format!("{:.3}", r.ns) } else { format!("{:.1}", r.ns) };
            let cloth =
                if r.cloth == IRREGULAR { format!("{} ({} particles)", r.cloth, r.particles) } else { r.cloth.into() };
            let _ = writeln!(s, "| {} | {cloth} | {ns} | {ratio} | {:.0} % |", r.backend, 100.0 * r.spread);
        }
        s.push('\n');
    }
    if !notes.is_empty() {
        s.push_str("## Not measured\n\n");
        for note in notes {
            let _ = writeln!(s, "- {note}");
        }
        s.push('\n');
    }
    s.push_str("![ns per particle-substep](mesh-vs-grid.png)\n");
    s
}

/// The rows as CSV.
pub fn csv(rows: &[Row]) -> String {
    let mut s = String::from("n,backend,cloth,particles,ns_per_particle_substep,spread\n");
    for r in rows {
        // The cloth's name has a comma: quoted.
        let _ = writeln!(s, "{},{},\"{}\",{},{:.3},{:.4}", r.n, r.backend, r.cloth, r.particles, r.ns, r.spread);
    }
    s
}

/// Bars: ns per particle-substep per (size, backend), a bar per cloth.
struct Bars<'a> {
    rows: &'a [Row],
    machine: &'a str,
}

impl Figure for Bars<'_> {
    fn size(&self) -> (u32, u32) {
        (1000, 600)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(err)?;
        let mut groups: Vec<(u32, &str)> = self.rows.iter().map(|r| (r.n, r.backend.as_str())).collect();
        groups.dedup();
        // The middle bar: the grid without the fused sweep (CPU) or the grid-only switches (GPU).
        let cloths = [GRID, GRID_KERNELS, GRID_TABLE, MESH, IRREGULAR];
        let colours = [
            RGBColor(40, 90, 170),
            RGBColor(120, 160, 220),
            RGBColor(120, 160, 220),
            RGBColor(220, 120, 40),
            RGBColor(90, 160, 80),
        ];
        // Bars a group: three, or four with an irregular mesh.
        let places = if self.rows.iter().any(|r| r.cloth == IRREGULAR) { 4.0 } else { 3.0 };
        let width = 0.8 / places;
        let top = self.rows.iter().map(|r| r.ns).fold(1.0, f64::max) * 1.15;
        let mut chart = ChartBuilder::on(root)
            .caption(format!("Grid against the grid as a mesh — {}", self.machine), (FONT, 20))
            .margin(12)
            .x_label_area_size(50)
            .y_label_area_size(70)
            // Room below zero for each group's name, centred under its bars.
            .build_cartesian_2d(0.0..groups.len() as f64, -0.08 * top..top)
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(0)
            .y_desc("ns per particle-substep")
            .label_style((FONT, 13))
            .draw()
            .map_err(err)?;
        let style = TextStyle::from((FONT, 14).into_font()).pos(Pos::new(HPos::Center, VPos::Center));
        let names = groups
            .iter()
            .enumerate()
            .map(|(g, (n, b))| Text::new(format!("{b}, n = {n}"), (g as f64 + 0.5, -0.04 * top), style.clone()));
        chart.draw_series(names).map_err(err)?;
        for (c, (cloth, colour)) in cloths.iter().zip(colours).enumerate() {
            let bars: Vec<Rectangle<(f64, f64)>> = groups
                .iter()
                .enumerate()
                .filter_map(|(g, (n, b))| {
                    let r = self.rows.iter().find(|r| r.n == *n && r.backend == *b && r.cloth == *cloth)?;
                    // The two middle cloths share the middle place.
                    let x0 = g as f64 + 0.1 + width * [0.0, 1.0, 1.0, 2.0, 3.0][c];
                    Some(Rectangle::new([(x0, 0.0), (x0 + 0.93 * width, r.ns)], colour.filled()))
                })
                .collect();
            if bars.is_empty() {
                continue;
            }
            chart
                .draw_series(bars)
                .map_err(err)?
                .label(*cloth)
                .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], colour.filled()));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .label_font((FONT, 14))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(err)?;
        Ok(())
    }
}

/// Writes mesh-vs-grid.{md,csv,svg,png} into `out`.
pub fn write(out: &std::path::Path, rows: &[Row], notes: &[String], machine: &str, repeat: u32) -> Result<()> {
    clothlab::files::write_bytes(&out.join("mesh-vs-grid.csv"), csv(rows).as_bytes())?;
    clothlab::files::write_bytes(&out.join("mesh-vs-grid.md"), report(rows, notes, machine, repeat).as_bytes())?;
    let (svg, png) = both(&Bars { rows, machine })?;
    clothlab::files::write_bytes(&out.join("mesh-vs-grid.svg"), svg.as_bytes())?;
    clothlab::files::write_bytes(&out.join("mesh-vs-grid.png"), &png)?;
    Ok(())
}

/// `bench --mesh-vs-grid`: [`measure`], [`write()`] and [`report`] with the mode's own
/// defaults: the size list 64 and 128 where left at the default, and the backends, if
/// left at all of them, the CPU ones and each API's optimized one.
pub fn run(args: &BenchArgs, request: &Request) -> Result<ExitCode> {
    let (base, params, backends, sizes) = (&request.base, &request.params, &request.backends[..], &request.sizes[..]);
    let defaults = BenchArgs::default_sizes();
    let sizes: Vec<u32> = if sizes == defaults.as_slice() { vec![64, 128] } else { sizes.to_vec() };
    let backends: Vec<Backend> = if all_backends(backends) { DEFAULT_BACKENDS.to_vec() } else { backends.to_vec() };
    let frames = args.iters.div_ceil(params.substeps).max(1);
    make_out_dir(&args.out)?;
    let irregular = args.irregular.as_deref().map(|f| irregular(base, f)).transpose()?;
    let (rows, notes) = measure(base, params, irregular.as_ref(), &backends, &sizes, frames, args.repeat)?;
    let machine = args.machine.clone().unwrap_or_else(cpu_label);
    write(&args.out, &rows, &notes, &machine, args.repeat)?;
    outln!("{}", report(&rows, &notes, &machine, args.repeat))?;
    outln!("wrote {}/mesh-vs-grid.{{md,csv,svg,png}}", args.out.display())?;
    Ok(ExitCode::SUCCESS)
}
