//! `clothlab sim`: simulate headless and print a summary.

use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Result, bail};
use clothlab::core::stats::{summarize, write_json, write_obj};
use clothlab::core::timing::SUBSTEP;
use clothlab::core::{StateField, crossings};
use clothlab::record::Recorder;
use clothlab::{AnySolver, Backend, MAX_STEPS, Sim, SimOptions};

use crate::cli::{SimArgs, StatsArg};
use crate::out::outln;

/// Runs `sim`.
pub fn sim(args: SimArgs) -> Result<ExitCode> {
    if args.steps == 0 || args.steps > MAX_STEPS {
        bail!("invalid --steps {}: must be in 1 ..= {MAX_STEPS}", args.steps);
    }
    // Check the output before simulating, so a bad path fails at once, not after the run;
    // the file itself is written only when complete (an interrupted run leaves the old one).
    let out = match &args.out {
        Some(path) => {
            let format = out_format(path)?;
            clothlab::files::check_writable(path)?;
            Some((path, format))
        }
        None => None,
    };
    let gpu = args.gpu.setup(args.backend)?;
    let mut sim = Sim::open(SimOptions {
        backend: args.backend,
        physics: args.physics.physics(),
        n: args.n,
        gpu,
        envs: args.envs,
        grad: false,
    })?;
    let scene = sim.scene().clone();
    let frames = args.steps.div_ceil(sim.params().substeps as u64);
    let substeps = frames * sim.params().substeps as u64;
    if let Some(k) = args.world.filter(|&k| k >= sim.envs()) {
        bail!("invalid --world {k}: the batch has {} worlds (0 ..= {})", sim.envs(), sim.envs() - 1);
    }
    if sim.envs() > 1 {
        return batch(&args, &mut sim, frames, out);
    }
    let mut recording = match &args.record {
        Some(path) => Some(sim.recorder(path, frames, args.record_every, args.world)?),
        None => None,
    };
    let cpu_path = match sim.solver() {
        AnySolver::Cpu(cpu) => Some(cpu.path()),
        _ => None,
    };
    let title = sim.title().map(str::to_owned);
    let any = sim.solver();
    let mut wall = std::time::Duration::ZERO;
    if let Some(rec) = &mut recording {
        rec.frame(0, |_| Ok(any.get().state()?))?;
    }
    // With --check-crossings: the most crossings in a frame, at which frame, and the first
    // frame with any.
    let mut most = (0usize, 0u64);
    let mut first = None;
    // The contact between triangles' pairs at each frame's last substep: their sum and most.
    let (mut pair_sum, mut pair_most) = (0usize, 0usize);
    // And the searches for them since the start (the pairs of one serve later substeps).
    let before = any.get_ref().contact_stats().map_or((0, 0), |c| (c.searches, c.refreshes));
    for f in 1..=frames {
        let t0 = Instant::now();
        any.get().step_frame()?;
        wall += t0.elapsed();
        if let Some(c) = any.get_ref().contact_stats() {
            pair_sum += c.pairs;
            pair_most = pair_most.max(c.pairs);
        }
        // Read back outside the timed part (a GPU solver waits for its frame here).
        if let Some(rec) = &mut recording {
            rec.frame(f, |_| Ok(any.get().state()?))?;
        }
        if args.check_crossings {
            let c = crossings::count(&any.get().field(StateField::Pos)?, &any.topology().triangles).pairs;
            if c > most.0 {
                most = (c, f);
            }
            if c > 0 && first.is_none() {
                first = Some(f);
            }
        }
    }
    let state = any.get().state()?;
    let summary = summarize(&state, any.topology());
    let np = scene.num_particles() as f64;
    let per_substep =
        any.get_ref().timings().get(SUBSTEP).map(|r| r.median_ns).unwrap_or(wall.as_nanos() as f64 / substeps as f64);

    outln!("backend        {}", any.get_ref().name())?;
    if let Some(path) = &cpu_path {
        outln!("cpu path       {path}")?;
    }
    if let Some(path) = &args.physics.scene {
        outln!("scene          {} ({})", title.as_deref().unwrap_or("untitled"), path.display())?;
    }
    match &scene.cloth.mesh {
        Some(mesh) if scene.cloth.is_mesh() => outln!(
            "mesh           {} ({np} particles, {} triangles, {} springs)",
            mesh.display(),
            any.topology().triangles.len(),
            any.topology().springs.len()
        )?,
        _ => outln!("grid           {n}x{n} ({np} particles)", n = scene.cloth.n)?,
    }
    // A scene of several cloths: each one's particles in the state (`--out`'s arrays).
    for (k, part) in any.topology().parts().iter().enumerate() {
        outln!("  cloth[{k}]     particles {}..{}: {}", part.first, part.first + part.count, part.label)?;
    }
    outln!("substeps       {substeps} ({frames} frames of {})", any.get_ref().params().substeps)?;
    outln!("wall time      {:.3} s", wall.as_secs_f64())?;
    outln!("time/substep   {:.1} us median ({:.2} ns per particle-substep)", per_substep / 1e3, per_substep / np)?;
    outln!("max strain     {:.4} (structural springs, |L|/rest - 1)", summary.max_strain)?;
    match scene.floor_y {
        Some(y) => outln!("lowest point   {:.4} m (floor at {y} m)", summary.lowest_y)?,
        None => outln!("lowest point   {:.4} m (no floor)", summary.lowest_y)?,
    }
    outln!(
        "NaN            {}",
        if summary.nan_count == 0 { "none".to_string() } else { format!("{} components", summary.nan_count) }
    )?;
    let last = crossings::count(&state.pos, &any.topology().triangles).pairs;
    outln!("crossings      {last} (edges through triangles they share no vertex with, final state)")?;
    if args.check_crossings {
        match first {
            Some(first) => outln!("  every frame  at most {} (frame {}); the first at frame {first}", most.0, most.1)?,
            None => outln!("  every frame  none in any of the {frames} frames")?,
        }
    }

    if let Some(c) = any.get_ref().contact_stats() {
        outln!(
            "contact pairs  {:.0} on average at the frames' last substeps, at most {pair_most} ({:.2} per particle; reach {:.1} mm)",
            pair_sum as f64 / frames as f64,
            pair_most as f64 / np,
            c.reach * 1e3
        )?;
        let (searches, refreshes) = (c.searches - before.0, c.refreshes - before.1);
        outln!(
            "  searches     {searches} in {substeps} substeps ({:.2} a frame), {refreshes} partial ({:.2} a frame){}",
            searches as f64 / frames as f64,
            refreshes as f64 / frames as f64,
            if c.kept > 0 {
                format!("; the last kept {} pairs within its reach and margin", c.kept)
            } else {
                String::new()
            }
        )?;
        outln!(
            "  last substep {} pairs: {} approaches slowed, {} pushed apart, {}",
            c.pairs,
            c.slowed,
            c.pushed,
            if c.shared > 0.0 {
                format!("moved as one by {:.2} mm (no vertex farther from it than its bound: none cut)", c.shared * 1e3)
            } else {
                format!("{} vertices' motion cut to their bound", c.clamped)
            }
        )?;
    }
    if let Some(last) = any.get_ref().substep_stats().last() {
        outln!(
            "GPU statistics max strain {:.4}, kinetic energy {:.4e} J (last substep, reduced by {})",
            last.max_strain,
            last.kinetic_energy,
            if args.gpu.stats == StatsArg::Atomics { "atomics" } else { "subgroups" }
        )?;
    }

    outln!("kernel              median us    min us    max us  samples")?;
    for r in any.get_ref().timings().rows {
        outln!(
            "  {:<16} {:>10.1} {:>9.1} {:>9.1} {:>8}",
            r.label,
            r.median_ns / 1e3,
            r.min_ns / 1e3,
            r.max_ns / 1e3,
            r.samples
        )?;
    }

    if let Some((path, format)) = out {
        clothlab::files::write_atomic(path, |w| match format {
            OutFormat::Obj => write_obj(w, &state, any.topology()),
            OutFormat::Json => write_json(w, &state),
        })?;
        outln!("state written  {}", path.display())?;
    }
    if let Some(rec) = recording {
        recorded(rec, any.topology(), &scene)?;
    }
    Ok(if summary.nan_count == 0 { ExitCode::SUCCESS } else { ExitCode::FAILURE })
}

/// `sim` of a batch of worlds: the worlds stepped together, what they took, and their
/// states summed up (the most strain, the lowest point, NaN and crossings of all).
fn batch(
    args: &SimArgs,
    sim: &mut Sim,
    frames: u64,
    out: Option<(&std::path::PathBuf, OutFormat)>,
) -> Result<ExitCode> {
    let envs = sim.envs();
    let mut recording = match &args.record {
        Some(path) => Some(sim.recorder(path, frames, args.record_every, args.world)?),
        None => None,
    };
    if let Some(rec) = &mut recording {
        sim.record_frame(rec, 0)?;
    }
    if let (Some((path, OutFormat::Obj)), None) = (&out, args.world) {
        bail!(
            "--out {}: an .obj holds one cloth; with --envs {envs} write .json (every world's state) or name one --world",
            path.display()
        );
    }
    let np = sim.num_particles();
    let mut most = (0usize, 0u64);
    let mut first = None;
    let mut wall = std::time::Duration::ZERO;
    for f in 1..=frames {
        let t0 = Instant::now();
        sim.step(1)?;
        wall += t0.elapsed();
        if let Some(rec) = &mut recording {
            sim.record_frame(rec, f)?;
        }
        if args.check_crossings {
            let c = sim.crossings()?;
            if c > most.0 {
                most = (c, f);
            }
            if c > 0 && first.is_none() {
                first = Some(f);
            }
        }
    }
    let substeps: Vec<u64> =
        (0..envs).map(|k| sim.world_params(k).map(|p| frames * p.substeps as u64)).collect::<Result<_>>()?;
    let world_substeps: u64 = substeps.iter().sum();
    let (mut max_strain, mut lowest, mut nan, mut crossed) = (0f32, f32::INFINITY, 0usize, 0usize);
    let mut all =
        clothlab::core::ClothState { n: 0, pos: Vec::new(), vel: Vec::new(), force: Vec::new(), normal: Vec::new() };
    for state in sim.world_states()? {
        let summary = summarize(&state, sim.topology());
        max_strain = max_strain.max(summary.max_strain);
        lowest = lowest.min(summary.lowest_y);
        nan += summary.nan_count;
        crossed += crossings::count(&state.pos, &sim.topology().triangles).pairs;
        all.n = state.n;
        all.pos.extend(state.pos);
        all.vel.extend(state.vel);
        all.force.extend(state.force);
        all.normal.extend(state.normal);
    }
    let scene = sim.scene().clone();
    outln!(
        "backend        {} ({envs} worlds, {})",
        sim.name(),
        match sim.backend() {
            Backend::Cpu => "one after another",
            Backend::CpuPar => "on rayon's threads",
            _ => "every kernel dispatched once for all",
        }
    )?;
    if let Some(path) = &args.physics.scene {
        outln!("scene          {} ({})", sim.title().unwrap_or("untitled"), path.display())?;
    }
    match &scene.cloth.mesh {
        Some(mesh) if scene.cloth.is_mesh() => outln!("mesh           {} ({np} particles a world)", mesh.display())?,
        _ => outln!("grid           {n}x{n} ({np} particles a world, {} in all)", np * envs, n = scene.cloth.n)?,
    }
    outln!("frames         {frames} ({world_substeps} world-substeps)")?;
    outln!("wall time      {:.3} s", wall.as_secs_f64())?;
    let per = wall.as_nanos() as f64 / world_substeps.max(1) as f64;
    outln!(
        "world-substep  {:.2} us ({:.0} world-substeps a second, {:.2} ns per particle-substep)",
        per / 1e3,
        1e9 / per,
        per / np as f64
    )?;
    outln!("max strain     {max_strain:.4} (structural springs, |L|/rest - 1; the most of any world)")?;
    match scene.floor_y {
        Some(y) => outln!("lowest point   {lowest:.4} m (floor at {y} m; the lowest of any world)")?,
        None => outln!("lowest point   {lowest:.4} m (no floor; the lowest of any world)")?,
    }
    outln!("NaN            {}", if nan == 0 { "none".to_string() } else { format!("{nan} components") })?;
    outln!("crossings      {crossed} (edges through triangles they share no vertex with, final states, all worlds)")?;
    if args.check_crossings {
        match first {
            Some(first) => outln!("  every frame  at most {} (frame {}); the first at frame {first}", most.0, most.1)?,
            None => outln!("  every frame  none in any of the {frames} frames")?,
        }
    }
    match (out, args.world) {
        (Some((path, format)), Some(k)) => {
            let state = sim.world_state(k)?;
            clothlab::files::write_atomic(path, |w| match format {
                OutFormat::Obj => write_obj(w, &state, sim.topology()),
                OutFormat::Json => write_json(w, &state),
            })?;
            outln!("state written  {} (world {k})", path.display())?;
        }
        (Some((path, _)), None) => {
            clothlab::files::write_atomic(path, |w| write_json(w, &all))?;
            outln!("state written  {} ({envs} worlds, world after world)", path.display())?;
        }
        (None, _) => {}
    }
    if let Some(rec) = recording {
        recorded(rec, sim.topology(), &scene)?;
    }
    Ok(if nan == 0 { ExitCode::SUCCESS } else { ExitCode::FAILURE })
}

/// Writes a run's recording and says so.
fn recorded(rec: Recorder, topo: &clothlab::core::ClothTopology, scene: &clothlab::core::Scene) -> Result<()> {
    let worlds = rec.worlds().to_vec();
    let (path, frames, bytes) = rec.finish(topo, scene)?;
    match worlds[..] {
        [k] if k > 0 => outln!("recorded       {} (world {k}, {frames} frames, {bytes} bytes)", path.display())?,
        [_] => outln!("recorded       {} ({frames} frames, {bytes} bytes)", path.display())?,
        _ => outln!(
            "recorded       {} ({} worlds on a grid, {frames} frames, {bytes} bytes)",
            path.display(),
            worlds.len()
        )?,
    }
    Ok(())
}

enum OutFormat {
    Obj,
    Json,
}

fn out_format(path: &Path) -> Result<OutFormat> {
    match path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).as_deref() {
        Some("obj") => Ok(OutFormat::Obj),
        Some("json") => Ok(OutFormat::Json),
        _ => bail!("--out {}: unknown format, use a .obj or .json file name", path.display()),
    }
}
