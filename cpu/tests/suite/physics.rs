//! The CPU reference against physics and against itself. Each tolerance says why it is
//! what it is.

use clothlab_core::grid::{Rows, SLOTS, STRAIN_SLOTS, SpringSlot, TETHER_SLOTS, Tether, V4};
use clothlab_core::stats::{max_strain, summarize};
use clothlab_core::step_params::StepParams;
use clothlab_core::{Pinning, Scene, SimParams, Solver, SpringKind, build};
use clothlab_cpu as cpu;
use clothlab_cpu::CpuSolver;
use clothlab_cpu::Exec;

/// Step constants for hand-made particle sets: no gravity, drag, damping, friction or
/// colliders unless a test sets them; the floor far away.
fn bare_params(n: u32, dt: f32, mass: f32) -> StepParams {
    StepParams {
        gravity: [0.0; 4],
        wind: [0.0; 4],
        grab_target: [0.0; 4],
        dt,
        damping: 0.0,
        air_drag: 0.0,
        particle_mass: mass,
        floor_y: -1e6,
        margin: 0.0,
        friction: 0.0,
        strain_limit: 0.1,
        n,
        num_spheres: 0,
        num_boxes: 0,
        grab_index: -1,
        self_thickness: 0.0,
        spacing: 1.0,
        inv_cell: 0.0,
        num_particles: n * n,
        strain_passes: 1,
        tile_substeps: 1,
        num_bodies: 0,
        num_rods: 0,
        contact: Default::default(),
    }
}

#[test]
fn free_fall_follows_half_g_t_squared() {
    // The whole solver on a free 2×2 cloth: uniform gravity deforms no spring, so every
    // particle falls freely. vel is set to the velocity at t = -dt/2 of a particle at
    // rest at t = 0 (Verlet in velocity form keeps half-step velocities), for which it is
    // exact on a parabola whatever dt is; what remains is f32 rounding: 20 steps of 50 ms
    // (1 s, 4.9 m of fall from y = 0) keep it near 1e-6.
    let params = SimParams { air_drag: 0.0, damping: 0.0, frame_dt: 0.05, substeps: 1, ..Default::default() };
    let mut scene = Scene::with_n(2);
    scene.cloth.pinning = Pinning::None;
    scene.cloth.top_center = [0.0, 0.0, 0.0];
    scene.floor_y = None;
    scene.spheres.clear();
    let mut s = CpuSolver::new(Exec::Serial, scene, params.clone()).unwrap();
    let dt = params.dt();
    let g = params.gravity[1];
    let mut st = s.state().unwrap();
    let y0 = st.pos[0][1];
    for v in st.vel.iter_mut() {
        *v = [0.0, -0.5 * g * dt, 0.0, 0.0]; // v(-dt/2) = -½ g dt
    }
    st.force = vec![[0.0; 4]; 4];
    s.set_state(&st).unwrap();
    let frames = 20;
    for _ in 0..frames {
        s.step_frame().unwrap();
    }
    let t = frames as f32 * params.frame_dt;
    let expect = y0 + 0.5 * g * t * t;
    let got = s.state().unwrap().pos[0][1];
    // The bound, 1e-5 relative to the distance fallen (20^1.5 · 6e-8 ≈ 5e-6).
    let rel = ((got - expect) / (expect - y0)).abs();
    assert!(rel < 1e-5, "free fall: y = {got}, expected {expect}, relative error {rel:e}");
}

#[test]
fn spring_mass_period_is_two_pi_sqrt_m_over_k() {
    // Particle 0 pinned, particle 1 on a spring of stiffness k to it, no gravity.
    let (m, k) = (0.2f32, 50.0f32);
    let period = 2.0 * std::f32::consts::PI * (m / k).sqrt(); // 0.3974 s
    let dt = period / 400.0; // ω dt = 0.0157: Verlet's frequency error ω²dt²/24 ≈ 1e-5
    let p = bare_params(2, dt, m);
    let rest = 1.0;
    // One spring: a row of one entry at each end (compressed rows, as a mesh's).
    let slots = Rows::compressed(
        &[
            vec![SpringSlot { neighbor: 1, rest, ks: k, kd: 0.0 }],
            vec![SpringSlot { neighbor: 0, rest, ks: k, kd: 0.0 }],
        ],
        None,
    );
    let mut pos: Vec<V4> = vec![[0.0, 0.0, 0.0, 0.0], [rest + 0.1, 0.0, 0.0, 1.0]];
    let mut vel = vec![[0.0f32; 4]; 2];
    let mut force = vec![[0.0f32; 4]; 2];
    // Record upward zero crossings of the displacement, interpolated linearly.
    let mut crossings = Vec::new();
    let mut last = pos[1][0] - rest;
    for step in 1..=4000 {
        force.iter_mut().for_each(|f| *f = [0.0; 4]);
        cpu::forces(Exec::Serial, &p, &pos, &vel, &mut force);
        cpu::springs(Exec::Serial, &slots, &pos, &vel, &mut force);
        cpu::integrate(Exec::Serial, &p, &force, &mut pos, &mut vel);
        let x = pos[1][0] - rest;
        if last < 0.0 && x >= 0.0 {
            crossings.push((step as f32 - x / (x - last)) * dt);
        }
        last = x;
    }
    assert!(crossings.len() >= 8, "only {} crossings", crossings.len());
    let measured = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f32;
    let rel = (measured - period).abs() / period;
    // The bound: 1 %. (Verlet's own error here is ~1e-5, interpolation ~1e-4.)
    assert!(rel < 0.01, "period {measured} s, expected {period} s ({:.3} %)", rel * 100.0);
}

#[test]
fn pins_hold_and_nothing_ends_below_the_floor_or_inside_a_sphere() {
    let scene = Scene::with_n(32);
    let params = SimParams::default();
    let mut s = CpuSolver::new(Exec::Serial, scene.clone(), params.clone()).unwrap();
    let start = s.state().unwrap();
    let pinned: Vec<usize> = (0..start.pos.len()).filter(|&i| start.pos[i][3] == 0.0).collect();
    assert_eq!(pinned.len(), 2);
    for _ in 0..300 {
        s.step_frame().unwrap();
        let st = s.state_ref();
        for &i in &pinned {
            assert_eq!(st.pos[i], start.pos[i], "pinned particle {i} moved");
        }
        for (i, p) in st.pos.iter().enumerate() {
            // Collisions push to the surface plus the margin (1 cm); the strain pass that
            // runs after `collide` moves a particle by far less than that per substep, so
            // the geometric surfaces themselves are never crossed.
            assert!(p[1] >= scene.floor_height(), "particle {i} below the floor: {p:?}");
            for sp in &scene.spheres {
                let d = ((p[0] - sp.center[0]).powi(2) + (p[1] - sp.center[1]).powi(2) + (p[2] - sp.center[2]).powi(2))
                    .sqrt();
                assert!(d >= sp.radius, "particle {i} inside sphere {sp:?}: distance {d}");
            }
        }
    }
}

/// Every particle's count of over-stretched springs, as the pass that follows reads them.
fn strain_counts(p: &StepParams, slots: &Rows<SpringSlot>, pos: &[V4]) -> Vec<f32> {
    let mut c = vec![0.0; pos.len()];
    cpu::strain_count(Exec::Serial, p, slots, pos, &mut c);
    c
}

#[test]
fn a_lone_overstretched_spring_is_within_the_limit_after_one_pass() {
    let mut p = bare_params(2, 1e-3, 1.0);
    p.strain_limit = 0.1;
    let rest = 0.5;
    // Fixed rows, as a grid's: the spring in the first slot of each end's row.
    let mut slots = vec![SpringSlot::EMPTY; 2 * SLOTS];
    slots[0] = SpringSlot { neighbor: 1, rest, ks: 1.0, kd: 0.0 };
    slots[SLOTS] = SpringSlot { neighbor: 0, rest, ks: 1.0, kd: 0.0 };
    let slots = Rows::fixed(slots, SLOTS, STRAIN_SLOTS);
    let tethers = vec![[Tether::EMPTY; TETHER_SLOTS]; 2];
    let pos: Vec<V4> = vec![[0.0, 0.0, 0.0, 1.0], [0.3, 0.9, 0.2, 1.0]];
    let mut out = pos.clone();
    let counts = strain_counts(&p, &slots, &pos);
    cpu::strain_limit(Exec::Serial, &p, &slots, &tethers, &pos, &counts, &mut out);
    let len =
        ((out[1][0] - out[0][0]).powi(2) + (out[1][1] - out[0][1]).powi(2) + (out[1][2] - out[0][2]).powi(2)).sqrt();
    // One f32 length computation and two corrections: 1e-6 m covers the rounding.
    assert!(len <= 1.1 * rest + 1e-6, "length {len} after one pass, bound {}", 1.1 * rest);
}

/// Runs strain passes until no structural spring exceeds `(1 + τ)·rest + 1e-6` or
/// `max_passes` is reached; returns the passes used and the max strain before and after.
fn strain_passes_until_within(
    st: &mut clothlab_core::ClothState,
    topo: &clothlab_core::ClothTopology,
    p: &StepParams,
    max_passes: usize,
) -> (usize, f32, f32) {
    let before = max_strain(st, topo, SpringKind::Structural);
    let mut scratch = st.pos.clone();
    let within = |st: &clothlab_core::ClothState| {
        topo.springs.iter().filter(|s| s.kind == SpringKind::Structural as u32).all(|s| {
            let (a, b) = (st.pos[s.a as usize], st.pos[s.b as usize]);
            let len = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            // 1e-6 m covers the f32 rounding of lengths of a few cm.
            len <= (1.0 + p.strain_limit) * s.rest + 1e-6
        })
    };
    let mut passes = 0;
    while passes < max_passes && !within(st) {
        let counts = strain_counts(p, &topo.slots, &st.pos);
        cpu::strain_limit(Exec::Serial, p, &topo.slots, &topo.tethers, &st.pos, &counts, &mut scratch);
        std::mem::swap(&mut st.pos, &mut scratch);
        passes += 1;
    }
    let after = max_strain(st, topo, SpringKind::Structural);
    assert!(within(st), "still over the limit after {passes} passes: max strain {before} -> {after}");
    (passes, before, after)
}

#[test]
fn strain_passes_hold_every_structural_spring_of_a_stretched_sheet() {
    // A free 12×12 sheet (no pins, so no tethers), stretched 1.3× and jittered by up to
    // ±0.25 of a spacing: every structural spring starts far over the limit. The passes
    // (the solver runs `strain_iterations` of them per substep) end with every structural
    // spring within (1 + τ)·rest + 1e-6.
    let mut scene = Scene::with_n(12);
    scene.cloth.pinning = Pinning::None;
    let params = SimParams::default();
    let (mut st, topo) = build(&scene, &params).unwrap();
    let spacing = scene.cloth.size / 11.0;
    let mut rng = 777u64;
    let mut rand = || {
        rng = rng.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((rng >> 40) as f32 / (1u64 << 24) as f32) - 0.5
    };
    let c = st.pos[0];
    for q in st.pos.iter_mut() {
        for k in 0..3 {
            q[k] = c[k] + (q[k] - c[k]) * 1.3 + 0.5 * spacing * rand();
        }
    }
    let p = StepParams::new(&params, &scene, None);
    // Measured: 358 passes (262 when each particle divided by its own count alone, which
    // did not keep the momentum).
    let (passes, before, after) = strain_passes_until_within(&mut st, &topo, &p, 600);
    println!("free sheet: strain {before:.4} -> {after:.4} in {passes} passes");
    assert!(before > 0.3, "the test sheet should start stretched ({before})");
}

#[test]
fn strain_passes_hold_a_sheet_stretched_away_from_its_pins() {
    // A 16×16 sheet hung at two corners, stretched 1.6× away from its pinned edge and
    // jittered: tethers and springs both act. The passes end with every structural
    // spring within (1 + τ)·rest + 1e-6.
    let scene = Scene::with_n(16);
    let params = SimParams::default();
    let (mut st, topo) = build(&scene, &params).unwrap();
    let mut rng = 12345u64;
    let mut rand = || {
        rng = rng.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((rng >> 40) as f32 / (1u64 << 24) as f32) - 0.5
    };
    let top = st.pos[0];
    for q in st.pos.iter_mut().filter(|q| q[3] != 0.0) {
        for k in 0..3 {
            q[k] = top[k] + (q[k] - top[k]) * 1.6 + 0.02 * rand();
        }
    }
    let p = StepParams::new(&params, &scene, None);
    // Measured: 628 passes (217 dividing by each particle's own count alone: a spring
    // between a particle with few stretched springs and one with many now moves as much as
    // the busier end allows; a solver runs a few passes per substep, and the tethers hold
    // the pins).
    let (passes, before, after) = strain_passes_until_within(&mut st, &topo, &p, 1000);
    println!("pinned sheet: strain {before:.4} -> {after:.4} in {passes} passes");
    assert!(before > 0.4, "the test sheet should start stretched ({before})");
}

#[test]
fn vertex_normals_of_a_flat_sheet_are_unit_and_on_one_side() {
    let scene = Scene::with_n(17);
    let (mut st, topo) = build(&scene, &SimParams::default()).unwrap();
    // Jitter in the plane: still flat, but no longer a regular grid.
    for (k, q) in st.pos.iter_mut().enumerate() {
        q[0] += 0.01 * ((k * 7 % 11) as f32 / 11.0 - 0.5);
        q[2] += 0.01 * ((k * 5 % 13) as f32 / 13.0 - 0.5);
    }
    let p = StepParams::new(&SimParams::default(), &scene, None);
    let mut face = vec![[f32::NAN; 4]; topo.triangles.len()];
    cpu::tri_normals(Exec::Serial, &topo.triangles, &st.pos, &mut face);
    cpu::vertex_normals(Exec::Serial, &p, &topo.face_slots, &face, &mut st.normal, &mut st.force);
    for (i, nrm) in st.normal.iter().enumerate() {
        let len = (nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]).sqrt();
        // One f32 normalisation: a few ulps.
        assert!((len - 1.0).abs() < 1e-6, "normal {i} has length {len}");
        // The sheet lies in y = const, so every normal is exactly ±y; all must be +y.
        assert!(nrm[1] > 0.999_999, "normal {i} = {nrm:?}");
    }
}

#[test]
fn wind_pushes_a_sheet_it_hits_and_not_one_it_grazes() {
    let scene = Scene::with_n(9);
    let (mut st, topo) = build(&scene, &SimParams::default()).unwrap();
    let mut face = vec![[0.0; 4]; topo.triangles.len()];
    cpu::tri_normals(Exec::Serial, &topo.triangles, &st.pos, &mut face);
    let coef = 0.5;
    for (wind, perpendicular) in [([0.0, 4.0, 0.0], true), ([3.0, 0.0, -2.0], false)] {
        let params = SimParams { wind, wind_coefficient: coef, ..Default::default() };
        let p = StepParams::new(&params, &scene, None);
        cpu::vertex_normals(Exec::Serial, &p, &topo.face_slots, &face, &mut st.normal, &mut st.force);
        let total: [f32; 3] = st.force.iter().fold([0.0; 3], |a, f| [a[0] + f[0], a[1] + f[1], a[2] + f[2]]);
        if perpendicular {
            // c · A · (n̂·w): the whole 2 m × 2 m sheet, to f32 summation rounding.
            let expect = coef * scene.cloth.size * scene.cloth.size * 4.0;
            assert!((total[1] - expect).abs() < 1e-4 * expect, "wind force {total:?}, expected y = {expect}");
            assert!(total[0].abs() < 1e-6 && total[2].abs() < 1e-6, "{total:?}");
        } else {
            // Face normals of a sheet at y = const are exactly ±y, so n̂·w is exactly 0.
            let max = st.force.iter().flat_map(|f| f[..3].iter()).fold(0.0f32, |m, v| m.max(v.abs()));
            assert_eq!(max, 0.0, "wind in the plane produced a force");
        }
    }
}

#[test]
fn gather_and_scatter_spring_forces_agree_to_rounding() {
    // The naive kernels' twin sums per spring, the optimized per particle: same forces up
    // to summation order. Up to 12 terms of magnitude ≲ F: |Δ| ≤ 12·ε·F, ε = 1.2e-7.
    let scene = Scene::with_n(20);
    let params = SimParams::default();
    let mut s = CpuSolver::new(Exec::Serial, scene, params.clone()).unwrap();
    for _ in 0..30 {
        s.step_frame().unwrap();
    }
    let st = s.state().unwrap();
    let topo = s.topology();
    let mut gather = vec![[0.0f32; 4]; st.pos.len()];
    let mut scatter = gather.clone();
    cpu::springs(Exec::Serial, &topo.slots, &st.pos, &st.vel, &mut gather);
    cpu::springs_scatter(&topo.springs, &st.pos, &st.vel, &mut scatter);
    let scale = gather.iter().flat_map(|f| f[..3].iter()).fold(0.0f32, |m, v| m.max(v.abs()));
    assert!(scale > 0.0);
    for (i, (g, c)) in gather.iter().zip(&scatter).enumerate() {
        for k in 0..3 {
            assert!((g[k] - c[k]).abs() <= 12.0 * f32::EPSILON * scale, "particle {i}: gather {g:?}, scatter {c:?}");
        }
    }
}

#[test]
fn serial_and_rayon_agree_bit_for_bit() {
    let params = SimParams::default();
    let mut a = CpuSolver::new(Exec::Serial, Scene::with_n(64), params.clone()).unwrap();
    let mut b = CpuSolver::new(Exec::Parallel, Scene::with_n(64), params.clone()).unwrap();
    let frames = 500u32.div_ceil(params.substeps); // 512 substeps
    for _ in 0..frames {
        a.step_frame().unwrap();
        b.step_frame().unwrap();
    }
    let (sa, sb) = (a.state().unwrap(), b.state().unwrap());
    let bits = |v: &Vec<V4>| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&sa.pos), bits(&sb.pos), "positions differ");
    assert_eq!(bits(&sa.vel), bits(&sb.vel), "velocities differ");
    assert_eq!(bits(&sa.normal), bits(&sb.normal), "normals differ");
    // And the run did something: the cloth has fallen from its start.
    let start = clothlab_core::build(&Scene::with_n(64), &params).unwrap().0;
    let moved = sa.pos.iter().zip(&start.pos).map(|(p, q)| (p[1] - q[1]).abs()).fold(0.0f32, f32::max);
    assert!(moved > 0.5, "cloth moved only {moved} m");
}

#[test]
fn ten_thousand_substeps_stay_finite_and_bounded() {
    let params = SimParams::default();
    let scene = Scene::with_n(64);
    let mut s = CpuSolver::new(Exec::Parallel, scene.clone(), params.clone()).unwrap();
    let frames = 10_000u32.div_ceil(params.substeps);
    let mut worst = 0.0f32;
    for f in 0..frames {
        s.step_frame().unwrap();
        if f % 25 == 0 || f == frames - 1 {
            let sum = summarize(s.state_ref(), s.topology());
            assert_eq!(sum.nan_count, 0, "NaN after frame {f}");
            worst = worst.max(sum.max_strain);
        }
    }
    let sum = summarize(s.state_ref(), s.topology());
    // Springs alone would let the corners' springs stretch without bound; the strain limit
    // (τ = 0.1) and tethers hold them. Measured on this scene: the worst structural strain
    // over the run is 0.110 (τ = 0.1 plus what one substep adds before the strain pass);
    // 0.2 leaves room for harmless changes and still catches a strain limit that stops
    // working (without tethers the corners reach 0.2 at n = 64).
    assert!(worst < 0.2, "max structural strain reached {worst}");
    assert!(sum.lowest_y >= scene.floor_height(), "below the floor: {}", sum.lowest_y);
    // At rest, nearly: the hanging cloth's kinetic energy has decayed.
    let st = s.state_ref();
    let vmax = st.vel.iter().map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()).fold(0.0f32, f32::max);
    println!("worst strain {worst:.3}, final max speed {vmax:.3} m/s");
    // Measured 0.09 m/s (the slow sway of a cloth draped over spheres); a strain limit
    // that jitters the particles next to the pins gives about 1 m/s.
    assert!(vmax < 0.3, "cloth still moving at {vmax} m/s after {} s", frames as f32 * params.frame_dt);
}

#[test]
fn row_fast_path_matches_the_twin_bit_for_bit() {
    // The solvers' row-wise springs (uniform interior fast path) must compute exactly what
    // the per-particle twin computes: same operations in the same order.
    for n in [5u32, 6, 33, 64] {
        let scene = Scene::with_n(n);
        let params = SimParams::default();
        let mut s = CpuSolver::new(Exec::Serial, scene, params.clone()).unwrap();
        for _ in 0..20 {
            s.step_frame().unwrap();
        }
        let st = s.state().unwrap();
        let topo = s.topology();
        let uni = topo.uniform_interior_slots();
        assert!(uni.is_some(), "a built grid has uniform interior slots");
        let mut lanes = cpu::Lanes::default();
        lanes.fill(Exec::Serial, n as usize, &st.pos, Some(&st.vel));
        let mut twin = st.force.clone();
        cpu::springs(Exec::Serial, &topo.slots, &st.pos, &st.vel, &mut twin);
        // And with `forces` fused in front.
        let p0 = StepParams::new(&params, s.scene(), None);
        let mut twin_fused = st.force.clone();
        cpu::forces(Exec::Serial, &p0, &st.pos, &st.vel, &mut twin_fused);
        cpu::springs(Exec::Serial, &topo.slots, &st.pos, &st.vel, &mut twin_fused);
        for exec in [Exec::Serial, Exec::Parallel] {
            for (fused, want) in [(None, &twin), (Some(&p0), &twin_fused)] {
                let mut rows = st.force.clone();
                let (slots, uni) = (&topo.slots, uni.as_ref());
                cpu::springs_rows(exec, n as usize, slots, uni, fused, &lanes, &st.pos, &st.vel, &mut rows);
                let bits = |v: &Vec<V4>| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(want), bits(&rows), "springs, n = {n}, {exec:?}, forces fused: {}", fused.is_some());
            }
        }
        // Strain limit, with a grabbed particle inside the interior (mobility 0 there).
        let grab = clothlab_core::Grab { particle: (n * n / 2 + n / 2), target: [0.0, 1.0, 0.0] };
        let p = StepParams::new(&params, s.scene(), Some(grab));
        // Stretch the sheet 1.2× away from its first pin so that springs and tethers act.
        let mut st = st.clone();
        let top = st.pos[0];
        for q in st.pos.iter_mut().filter(|q| q[3] != 0.0) {
            for k in 0..3 {
                q[k] = top[k] + (q[k] - top[k]) * 1.2;
            }
        }
        let mut lanes_p = cpu::Lanes::default();
        lanes_p.fill(Exec::Parallel, n as usize, &st.pos, None);
        let mut twin = st.pos.clone();
        let counts = strain_counts(&p, &topo.slots, &st.pos);
        cpu::strain_limit(Exec::Serial, &p, &topo.slots, &topo.tethers, &st.pos, &counts, &mut twin);
        assert_ne!(twin, st.pos, "the pass should change something");
        for exec in [Exec::Serial, Exec::Parallel] {
            let mut rows = st.pos.clone();
            cpu::strain_limit_rows(
                exec,
                &p,
                &topo.slots,
                uni.as_ref(),
                &topo.tethers,
                &lanes_p,
                &st.pos,
                &counts,
                &mut rows,
            );
            let bits = |v: &Vec<V4>| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&twin), bits(&rows), "strain_limit, n = {n}, {exec:?}");
        }
        // Normals and wind (wind on, so the wind path is compared too).
        let windy = SimParams { wind: [1.5, -0.5, 2.0], ..params.clone() };
        let p = StepParams::new(&windy, s.scene(), None);
        let mut face = vec![[0.0; 4]; topo.triangles.len()];
        let (mut nrm, mut wind) = (st.normal.clone(), st.force.clone());
        cpu::tri_normals(Exec::Serial, &topo.triangles, &st.pos, &mut face);
        cpu::vertex_normals(Exec::Serial, &p, &topo.face_slots, &face, &mut nrm, &mut wind);
        assert!(wind.iter().any(|f| f[0] != 0.0), "wind should act on the stretched sheet");
        for exec in [Exec::Serial, Exec::Parallel] {
            let mut faces = cpu::FaceLanes::default();
            cpu::tri_normals_lanes(exec, n as usize, &lanes_p, &mut faces);
            for (t, f) in face.iter().enumerate() {
                assert_eq!(f.map(f32::to_bits), faces.get(t).map(f32::to_bits), "face {t}, n = {n}");
            }
            let (mut nrm2, mut wind2) = (vec![[0.0; 4]; st.pos.len()], vec![[0.0; 4]; st.pos.len()]);
            cpu::vertex_normals_rows(exec, &p, &topo.face_slots, &faces, &mut nrm2, &mut wind2);
            let bits = |v: &Vec<V4>| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&nrm), bits(&nrm2), "normals, n = {n}, {exec:?}");
            assert_eq!(bits(&wind), bits(&wind2), "wind, n = {n}, {exec:?}");
        }
    }
}

#[test]
fn a_solver_substep_is_the_twin_kernels_in_order() {
    // The solvers fuse kernels and run SIMD row paths; the GPU backends are compared with
    // the plain twins. This pins the two together: one substep of each solver equals the
    // seven twins run one after another, bit for bit, with wind on and a grab active.
    let n = 40u32;
    let params = SimParams { wind: [2.0, 0.0, 1.0], ..Default::default() };
    let scene = Scene::with_n(n);
    for exec in [Exec::Serial, Exec::Parallel] {
        let mut s = CpuSolver::new(exec, scene.clone(), params.clone()).unwrap();
        for _ in 0..10 {
            s.step_frame().unwrap();
        }
        let grab = clothlab_core::Grab { particle: n * n - n / 2, target: [0.2, 0.9, 0.4] };
        s.set_grab(Some(grab));
        let mut st = s.state().unwrap();
        let topo = s.topology().clone();
        let p = StepParams::new(&params, &scene, Some(grab));
        cpu::forces(Exec::Serial, &p, &st.pos, &st.vel, &mut st.force);
        cpu::springs(Exec::Serial, &topo.slots, &st.pos, &st.vel, &mut st.force);
        cpu::integrate(Exec::Serial, &p, &st.force, &mut st.pos, &mut st.vel);
        cpu::collide(Exec::Serial, &p, cpu::Colliders::new(&scene.spheres, &scene.boxes), &mut st.pos, &mut st.vel);
        let mut scratch = st.pos.clone();
        for _ in 0..params.strain_iterations {
            let counts = strain_counts(&p, &topo.slots, &st.pos);
            cpu::strain_limit(Exec::Serial, &p, &topo.slots, &topo.tethers, &st.pos, &counts, &mut scratch);
            cpu::strain_vel(Exec::Serial, &p, &st.pos, &scratch, &mut st.vel);
            std::mem::swap(&mut st.pos, &mut scratch);
        }
        let mut face = vec![[0.0; 4]; topo.triangles.len()];
        cpu::tri_normals(Exec::Serial, &topo.triangles, &st.pos, &mut face);
        cpu::vertex_normals(Exec::Serial, &p, &topo.face_slots, &face, &mut st.normal, &mut st.force);
        s.substep();
        let got = s.state().unwrap();
        let bits = |v: &Vec<V4>| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&st.pos), bits(&got.pos), "{exec:?}: positions");
        assert_eq!(bits(&st.vel), bits(&got.vel), "{exec:?}: velocities");
        assert_eq!(bits(&st.normal), bits(&got.normal), "{exec:?}: normals");
        assert_eq!(bits(&st.force), bits(&got.force), "{exec:?}: wind force");
        assert_eq!(got.pos[grab.particle as usize][..3], grab.target, "the grabbed particle is on its target");
    }
}
