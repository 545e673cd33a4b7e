//! Vertex Block Descent's CPU reference (`cpu::vbd`) against
//! analytic cases: its colourings valid on grids and irregular meshes, free fall exactly
//! implicit Euler's recurrence, a spring's oscillation decaying no faster than implicit
//! Euler's, momentum with only internal forces, a hanging cloth's strain.

use clothlab_core::grid::{SpringSlot, V4};
use clothlab_core::step_params::StepParams;
use clothlab_core::{Pinning, Scene, SceneFile, SimParams, build};
use clothlab_cpu::vbd::{colouring, colouring_is_valid, vbd_substep};

fn scene_file(name: &str) -> SceneFile {
    SceneFile::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes").join(name)).unwrap()
}

#[test]
fn the_colourings_are_valid_on_grids_and_irregular_meshes() {
    for n in [3u32, 7, 10] {
        let (_, topo) = build(&Scene::with_n(n), &SimParams::default()).unwrap();
        let c = colouring(&topo);
        assert_eq!(c.len(), 9, "n = {n}: (i mod 3, j mod 3)");
        assert!(colouring_is_valid(&topo, &c), "n = {n}");
        assert_eq!(topo.colours.lists(), c, "n = {n}: the topology's colouring (what the GPU sweeps)");
    }
    // The fan (a centre of 64 edges and 64 bending springs), the Delaunay cape, two cloths.
    for (name, most) in [("mesh-fan.toml", 140), ("mesh-cape.toml", 24), ("two-cloths.toml", 24)] {
        let file = scene_file(name);
        let (_, topo) = build(&file.scene, &file.params).unwrap();
        let c = colouring(&topo);
        println!("{name}: {} colours", c.len());
        assert!(colouring_is_valid(&topo, &c), "{name}");
        assert_eq!(topo.colours.lists(), c, "{name}: the topology's colouring");
        // Greedy needs at most one more colour than the largest row.
        let largest = (0..topo.num_particles()).map(|i| topo.slots.row(i).len()).max().unwrap();
        assert!(c.len() <= largest + 1 && c.len() <= most, "{name}: {} colours, rows up to {largest}", c.len());
    }
    // Two neighbours in one colour are caught, as is a particle left out or listed twice.
    let (_, topo) = build(&Scene::with_n(4), &SimParams::default()).unwrap();
    let mut c = colouring(&topo);
    let moved = c[1].pop().unwrap();
    c[0].push(moved);
    assert!(!colouring_is_valid(&topo, &c), "a colour with two neighbours");
    let mut c = colouring(&topo);
    c[0].pop();
    assert!(!colouring_is_valid(&topo, &c), "a particle left out");
}

/// A free 10 × 10 cloth, no drag, no damping: with no spring stretched VBD's minimiser is
/// the inertial prediction, so every particle follows implicit Euler's recurrence
/// `vₖ = v₀ + k h g`, `xₖ = x₀ + Σ h vₖ`, at 3.7 m and at 50 m (where an f32 position
/// resolves 3.8 µm: the displacement is summed apart from x).
#[test]
fn a_free_cloth_falls_by_implicit_eulers_recurrence() {
    for height in [3.7f32, 50.0] {
        let mut scene = Scene::with_n(10);
        scene.cloth.pinning = Pinning::None;
        scene.cloth.top_center = [0.0, height, 0.0];
        scene.cloth.velocity = [0.3, 0.5, 0.0];
        (scene.floor_y, scene.spheres) = (None, Vec::new());
        let params = SimParams { air_drag: 0.0, damping: 0.0, ..SimParams::default() };
        let (state, topo) = build(&scene, &params).unwrap();
        let p = StepParams::new(&params, &scene, None);
        let colours = colouring(&topo);
        let (mut pos, mut vel) = (state.pos.clone(), state.vel.clone());
        let steps = 64;
        for _ in 0..steps {
            vbd_substep(&p, &topo, &colours, 4, &mut pos, &mut vel);
        }
        let (h, g, k) = (p.dt as f64, p.gravity[1] as f64, steps as f64);
        let want_dy = h * k * 0.5 + h * h * g * k * (k + 1.0) / 2.0;
        let want_vy = 0.5 + k * h * g;
        let mut worst = 0.0f64;
        for (a, b) in state.pos.iter().zip(&pos) {
            worst = worst.max(((b[1] - a[1]) as f64 - want_dy).abs());
        }
        let vy = vel.iter().map(|v| v[1] as f64).fold(0.0, |a: f64, v| a.max((v - want_vy).abs()));
        println!("height {height}: drop {want_dy:.5} m, worst error {worst:.2e} m, velocity error {vy:.2e} m/s");
        // What is left is the rounding of the final position, x⁰ + D, to f32 (its ulp:
        // 2.4e-7 m at 3.7 m, 3.8e-6 m at 50 m; measured 1.5e-7 and 3.9e-7 m): two ulps.
        // The velocity never touches x: measured 1.6e-7 m/s of −0.15 m/s; bound 1e-6.
        let ulp = f32::from_bits(height.to_bits() + 1) - height;
        assert!(worst < 2.0 * ulp as f64, "height {height}: {worst} m");
        assert!(vy < 1e-6, "height {height}: {vy}");
    }
}

/// One spring, one end pinned: `x'' = −ω² x`. Implicit Euler damps the amplitude by
/// `(1 + h²ω²)^(−1/2)` a step; VBD converged is implicit Euler, and fewer iterations stop
/// short of its minimiser, never past it, so it damps no faster. Here 40 steps a period,
/// over two periods (amplitude 0.1 → 0.0603 m): one free vertex's block is the whole
/// problem, so even one iteration lands on implicit Euler (measured equal to 1e-5 m at
/// 1, 2 and 20 iterations).
#[test]
fn a_springs_oscillation_decays_no_faster_than_implicit_eulers() {
    let params = SimParams {
        air_drag: 0.0,
        damping: 0.0,
        gravity: [0.0; 3],
        structural_damping: 0.0,
        shear_damping: 0.0,
        bend_damping: 0.0,
        ..SimParams::default()
    };
    let mut scene = Scene::with_n(2);
    (scene.floor_y, scene.spheres) = (None, Vec::new());
    let (_, mut topo) = build(&scene, &params).unwrap();
    let mut p = StepParams::new(&params, &scene, None);
    let m = p.particle_mass as f64;
    let omega = 2.0 * std::f64::consts::PI;
    let k = (m * omega * omega) as f32;
    topo.slots.entries_mut().fill(SpringSlot::EMPTY);
    topo.slots.row_mut(1)[0] = SpringSlot { neighbor: 0, rest: 1.0, ks: k, kd: 0.0 };
    let h = 1.0 / 40.0;
    p.dt = h as f32;
    let colours = colouring(&topo);
    let amplitude = 0.1f64;
    let run = |iterations: u32| {
        let mut pos: Vec<V4> = vec![
            [0.0, 0.0, 0.0, 0.0],
            [1.0 + amplitude as f32, 0.0, 0.0, 1.0],
            [5.0, 5.0, 5.0, 0.0],
            [6.0, 5.0, 5.0, 0.0],
        ];
        let mut vel = vec![[0.0f32; 4]; 4];
        let mut last = 0.0f64;
        for step in 0..80 {
            vbd_substep(&p, &topo, &colours, iterations, &mut pos, &mut vel);
            if step >= 40 {
                last = last.max((pos[1][0] as f64 - 1.0).abs());
            }
        }
        last
    };
    // Implicit Euler on the same oscillator, in f64.
    let (mut x, mut v, mut ie) = (amplitude, 0.0f64, 0.0f64);
    for step in 0..80 {
        let next = (x + h * v) / (1.0 + h * h * omega * omega);
        v = (next - x) / h;
        x = next;
        if step >= 40 {
            ie = ie.max(x.abs());
        }
    }
    for iterations in [1u32, 2, 20] {
        let a = run(iterations);
        println!("{iterations:2} iterations: amplitude {a:.5} m after two periods, implicit Euler {ie:.5} m");
        // f32 positions near 1 m: 1e-6 m of rounding over 80 steps.
        assert!(a >= ie - 1e-5, "{iterations} iterations: {a} < implicit Euler's {ie}");
        if iterations == 20 {
            assert!((a - ie).abs() < 1e-3 * amplitude, "converged VBD is implicit Euler: {a} against {ie}");
        }
    }
}

/// A free cloth with no gravity, disturbed and moving: only the springs (and their damping)
/// act. Each local step moves one particle, so momentum is kept only as far as the
/// iterations converge: measured 1.2e-4 of the momentum at 5 iterations and 4.9e-6 at 40
/// over 32 substeps (bounds 5e-4 and 5e-5, and 40 closer than 5). When the solve stepped
/// the f32 positions themselves (not the displacements) their roundings lost 3.7e-3 at 40
/// iterations; the paper's damping (on each vertex's own displacement) lost 0.97 of it.
#[test]
fn momentum_with_only_internal_forces_is_kept_to_what_the_iterations_leave() {
    let mut scene = Scene::with_n(8);
    scene.cloth.pinning = Pinning::None;
    (scene.floor_y, scene.spheres) = (None, Vec::new());
    let params = SimParams { air_drag: 0.0, damping: 0.0, gravity: [0.0; 3], ..SimParams::default() };
    let (state, topo) = build(&scene, &params).unwrap();
    let p = StepParams::new(&params, &scene, None);
    let colours = colouring(&topo);
    let jitter = |k: usize, c: usize| ((k * 7919 + c * 104729) % 1000) as f32 * 2e-5;
    let pos0: Vec<V4> =
        state.pos.iter().enumerate().map(|(k, x)| [x[0] + jitter(k, 0), x[1] + jitter(k, 1), x[2], x[3]]).collect();
    let vel0: Vec<V4> = (0..pos0.len()).map(|k| [0.4 + jitter(k, 2) * 50.0, 0.0, -0.2, 0.0]).collect();
    let momentum = |vel: &[V4]| {
        let mut s = [0.0f64; 3];
        for v in vel {
            (0..3).for_each(|c| s[c] += v[c] as f64);
        }
        s
    };
    let start = momentum(&vel0);
    let size = start.iter().map(|c| c * c).sum::<f64>().sqrt();
    let mut drifts = Vec::new();
    for (iterations, bound) in [(5u32, 5e-4), (40, 5e-5)] {
        let (mut pos, mut vel) = (pos0.clone(), vel0.clone());
        for _ in 0..32 {
            vbd_substep(&p, &topo, &colours, iterations, &mut pos, &mut vel);
        }
        let end = momentum(&vel);
        let drift = (0..3).map(|c| (end[c] - start[c]).powi(2)).sum::<f64>().sqrt() / size;
        println!("{iterations} iterations: momentum changed by {drift:.2e} of itself over 32 substeps");
        assert!(drift < bound, "{iterations} iterations: {drift}");
        drifts.push(drift);
    }
    assert!(drifts[1] < drifts[0], "more iterations, closer to implicit Euler's momentum: {drifts:?}");
}

/// The largest structural strain of `scene` hung for `frames` frames with `params` on the
/// CPU solver.
fn hung_strain(scene: &Scene, params: SimParams, frames: u32) -> f32 {
    let mut solver = clothlab_cpu::CpuSolver::new(clothlab_cpu::Exec::Parallel, scene.clone(), params).unwrap();
    for _ in 0..frames {
        clothlab_core::Solver::step_frame(&mut solver).unwrap();
    }
    let end = clothlab_core::Solver::state(&mut solver).unwrap();
    let topo = solver.topology();
    let p = |k: u32| glam::Vec3::from_slice(&end.pos[k as usize][..3]);
    topo.springs
        .iter()
        .filter(|s| s.kind == clothlab_core::SpringKind::Structural as u32)
        .map(|s| p(s.a).distance(p(s.b)) / s.rest - 1.0)
        .fold(0.0f32, f32::max)
}

/// A hanging cloth with the strain limit off: VBD minimises implicit Euler's energy, so
/// once its sweeps converge it hangs about as implicit Euler does (clothlab's implicit is
/// one Newton step solved by CG, 64 iterations here: the linearisation, not the
/// minimiser, so they differ by a few per cent). Measured on the 32 × 32 grid hanging
/// from its corners with no colliders after 1 s: VBD 1 iteration 0.254, 8 iterations
/// 0.156; implicit 0.159. At 8 iterations within 5 % of implicit Euler's; one iteration
/// stretches it > 30 % further (so the check can fail). The Delaunay cape (a vertex of 1
/// to 8 triangles): 0.1948 against 0.1949, within 5 % too (its own test, so that the
/// harness runs the two halves side by side).
#[test]
fn a_hanging_cloth_at_8_iterations_stretches_as_implicit_euler_does() {
    let mut scene = Scene::with_n(32);
    (scene.spheres, scene.boxes) = (Vec::new(), Vec::new());
    let base = SimParams { strain_iterations: 0, cg_iterations: 64, ..SimParams::default() };
    let with = |integrator, vbd_iterations| SimParams { integrator, vbd_iterations, ..base.clone() };
    let implicit = hung_strain(&scene, with(clothlab_core::Integrator::Implicit, 8), 60);
    let one = hung_strain(&scene, with(clothlab_core::Integrator::Vbd, 1), 60);
    let eight = hung_strain(&scene, with(clothlab_core::Integrator::Vbd, 8), 60);
    println!("grid n = 32: max strain implicit {implicit:.4}, vbd 1 iteration {one:.4}, 8 iterations {eight:.4}");
    assert!((eight - implicit).abs() < 0.05 * implicit, "vbd×8 {eight} against implicit {implicit}");
    assert!(one > 1.3 * implicit, "one VBD iteration should be far from converged: {one} against {implicit}");
}

/// The cape of [`a_hanging_cloth_at_8_iterations_stretches_as_implicit_euler_does`].
#[test]
fn a_hanging_mesh_at_8_iterations_stretches_as_implicit_euler_does() {
    let file = scene_file("mesh-cape.toml");
    let mut cape = file.scene;
    cape.spheres.clear();
    let base = SimParams { wind: [0.0; 3], strain_iterations: 0, cg_iterations: 64, ..file.params };
    let with = |integrator| SimParams { integrator, vbd_iterations: 8, ..base.clone() };
    let implicit = hung_strain(&cape, with(clothlab_core::Integrator::Implicit), 60);
    let vbd = hung_strain(&cape, with(clothlab_core::Integrator::Vbd), 60);
    println!("cape: max edge strain implicit {implicit:.4}, vbd×8 {vbd:.4}");
    assert!((vbd - implicit).abs() < 0.05 * implicit, "cape: vbd×8 {vbd} against implicit {implicit}");
}

/// A cloth lying flat on the floor, thrown sideways at 1 m/s: the contact is a penalty
/// energy in VBD's local solve and its friction the paper's smoothed Coulomb friction
/// (μ = `friction`), so the cloth slides `v²/(2μg)` (0.127 m at μ = 0.4) and stops after
/// `v/(μg)` (0.255 s); with μ = 0 it slides on at 1 m/s. It rests on the penalty, within
/// its reach beyond the margin (`CONTACT_REACH`): above `floor + margin`, where `collide`'s
/// projection (kept as the fallback) would act, and below `floor + 1.1 margin`.
/// Measured: 0.12694 m (0.4 % short) and 0.50000 m, resting at 1.1 margins (bounds: the
/// slide within 2 % — implicit Euler's first-order error over 0.255 s at 960 substeps
/// per second and the smoothing below 0.01 m/s — and the free slide within 0.1 %). With
/// the normal force taken at the iterate (not the block's step) it slid 0.1126 m.
#[test]
fn a_cloth_thrown_along_the_floor_slides_as_coulomb_friction_says() {
    let mut scene = Scene::with_n(8);
    scene.cloth.pinning = Pinning::None;
    scene.cloth.size = 0.3;
    scene.cloth.down = [0.0, 0.0, 1.0];
    scene.cloth.velocity = [1.0, 0.0, 0.0];
    scene.spheres.clear();
    scene.boxes.clear();
    scene.floor_y = Some(0.0);
    let base = SimParams {
        integrator: clothlab_core::Integrator::Vbd,
        air_drag: 0.0,
        damping: 0.0,
        collision_margin: 0.01,
        ..SimParams::default()
    };
    scene.cloth.top_center = [0.0, base.collision_margin * 1.1 + 1e-5, 0.0];
    let g = -base.gravity[1] as f64;
    for mu in [0.4f32, 0.0] {
        let params = SimParams { friction: mu, ..base.clone() };
        let mut solver = clothlab_cpu::CpuSolver::new(clothlab_cpu::Exec::Serial, scene.clone(), params).unwrap();
        let x0 = clothlab_core::Solver::state(&mut solver).unwrap().pos;
        let frames = 30;
        for _ in 0..frames {
            clothlab_core::Solver::step_frame(&mut solver).unwrap();
        }
        let end = clothlab_core::Solver::state(&mut solver).unwrap();
        let slide = end.pos.iter().zip(&x0).map(|(a, b)| (a[0] - b[0]) as f64).sum::<f64>() / x0.len() as f64;
        let (lo, hi) = end.pos.iter().fold((f32::MAX, f32::MIN), |(lo, hi), x| (lo.min(x[1]), hi.max(x[1])));
        let t = frames as f64 * base.frame_dt as f64;
        let want = if mu > 0.0 { 1.0 / (2.0 * mu as f64 * g) } else { t };
        println!("μ = {mu}: slid {slide:.5} m (Coulomb {want:.5} m), heights {lo:.6} … {hi:.6} m");
        let bound = if mu > 0.0 { 0.02 } else { 1e-3 };
        assert!((slide - want).abs() < bound * want, "μ = {mu}: slid {slide} m, want {want} m");
        let margin = base.collision_margin;
        assert!(lo > margin && hi < margin * 1.1, "μ = {mu}: heights {lo} … {hi} m");
    }
}

/// The paper's Chebyshev acceleration (`vbd_rho`): its weights are the recurrence's, free
/// fall stays implicit Euler's (the extrapolation of equal displacements is that
/// displacement; only rounding-level steps differ), and on a stiff cloth in motion 16
/// accelerated sweeps come closer to
/// the converged substep (64 sweeps) than 16 plain ones. Measured (n = 64, physical
/// stiffness, h = 1/240 s, no damping): 2.36e-3 m plain, 5.6e-5 m with ρ = 0.9 (bound: a
/// tenth of the plain sweeps' distance). On an easier problem (n = 32) plain sweeps
/// converge in 16 by themselves and the acceleration does not help (docs/parameters.md).
#[test]
fn chebyshev_acceleration_converges_faster_and_keeps_free_fall() {
    use clothlab_core::{Integrator, Solver, StiffnessUnits};
    use clothlab_cpu::vbd::chebyshev_omega;
    use clothlab_cpu::{CpuSolver, Exec};
    let rho = 0.9f32;
    assert_eq!(chebyshev_omega(1, rho), 1.0);
    assert_eq!(chebyshev_omega(2, rho), 2.0 / (2.0 - rho * rho));
    assert_eq!(chebyshev_omega(3, rho), 4.0 / (4.0 - rho * rho * chebyshev_omega(2, rho)));
    // Free fall: a free cloth with ρ = 0.9 against ρ = 0, bit for bit.
    let mut scene = Scene::with_n(10);
    scene.cloth.pinning = Pinning::None;
    (scene.floor_y, scene.spheres) = (None, Vec::new());
    let free = SimParams { integrator: Integrator::Vbd, air_drag: 0.0, damping: 0.0, ..SimParams::default() };
    let fall = |rho: f32| {
        let mut s = CpuSolver::new(Exec::Serial, scene.clone(), SimParams { vbd_rho: rho, ..free.clone() }).unwrap();
        for _ in 0..4 {
            s.step_frame().unwrap();
        }
        s.state().unwrap().pos
    };
    let (with, without) = (fall(0.9), fall(0.0));
    let apart =
        with.iter().zip(&without).flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs())).fold(0.0, f32::max);
    println!("free fall with and without the acceleration: {apart:.2e} m apart");
    // The springs see only the rounding of the positions, which the extrapolation moves
    // by ulps: measured 6e-8 m at 2.2 m (ulp 2.4e-7 m); bound 4 ulps.
    assert!(apart <= 4.0 * 2.4e-7, "free fall {apart} m apart with the acceleration");
    // A stiff cloth in motion: one substep from the same state.
    let mut scene = Scene::with_n(64);
    (scene.spheres, scene.boxes, scene.floor_y) = (Vec::new(), Vec::new(), None);
    let base = SimParams {
        integrator: Integrator::Vbd,
        stiffness_units: StiffnessUnits::Physical,
        air_drag: 0.0,
        damping: 0.0,
        structural_damping: 0.0,
        shear_damping: 0.0,
        bend_damping: 0.0,
        strain_iterations: 0,
        vbd_iterations: 16,
        ..SimParams::default()
    };
    let mut warm = CpuSolver::new(Exec::Parallel, scene.clone(), base.clone()).unwrap();
    for _ in 0..20 {
        warm.step_frame().unwrap();
    }
    let state = warm.state().unwrap();
    let one = SimParams { frame_dt: 1.0 / 240.0, substeps: 1, ..base };
    let substep = |iterations: u32, rho: f32| {
        let p = SimParams { vbd_iterations: iterations, vbd_rho: rho, ..one.clone() };
        let mut s = CpuSolver::new(Exec::Serial, scene.clone(), p).unwrap();
        s.set_state(&state).unwrap();
        s.step_frame().unwrap();
        s.state().unwrap().pos
    };
    let distance = |a: &[V4], b: &[V4]| {
        a.iter()
            .zip(b)
            .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]) as f64).map(|d| d * d).sum::<f64>())
            .sum::<f64>()
            .sqrt()
    };
    let converged = substep(64, 0.0);
    let plain = distance(&substep(16, 0.0), &converged);
    let accelerated = distance(&substep(16, rho), &converged);
    println!("16 sweeps: {plain:.3e} m from the converged substep plain, {accelerated:.3e} m with ρ = {rho}");
    assert!(accelerated < 0.1 * plain, "accelerated {accelerated} against plain {plain}");
}
