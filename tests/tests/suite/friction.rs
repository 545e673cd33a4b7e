//! Coulomb friction at contacts (`static_friction`, `kinetic_friction`;
//! `core::cpu::integrate::coulomb_contact`): analytic cases on every backend — a cloth
//! sliding on the floor slows at μk·g and stops where v0²/(2 μk g) says, a slope holds it
//! below tan θ = μs without creeping and lets it slide at g (sin θ − μk cos θ) above, a
//! table that moves carries it once kinetic friction has brought it to the table's
//! speed — and the GPU recipes bit for bit against the CPU with Coulomb contacts on
//! moving colliders.

use clothlab_core::scene::{ColliderId, Pinning};
use clothlab_core::{ClothState, Integrator, Motion, Scene, SimParams, Solver};
use clothlab_tests::{TABLE_V, assert_checks, backend, backends, mean, moving_table, still_air};

const G: f64 = 9.81;
const MU_S: f32 = 0.5;
const MU_K: f32 = 0.3;

/// Contacts alone act, with Coulomb's coefficients μs and μk (the share 0: unused).
fn coulomb(mu_s: f32, mu_k: f32) -> SimParams {
    SimParams { static_friction: mu_s, kinetic_friction: mu_k, ..still_air(0.0) }
}

/// A 0.2 m cloth of 8 × 8 lying on the floor at the margin (in contact from the first
/// substep), every particle moving at `v0` along x.
fn on_the_floor(v0: f32) -> Scene {
    let mut sc = Scene::with_n(8);
    sc.cloth.size = 0.2;
    sc.cloth.pinning = Pinning::None;
    sc.cloth.top_center = [0.0, SimParams::default().collision_margin, -0.1];
    sc.cloth.velocity = [v0, 0.0, 0.0];
    sc.floor_y = Some(0.0);
    sc.spheres.clear();
    sc.boxes.clear();
    sc
}

fn run(s: &mut dyn Solver, frames: u32) -> ClothState {
    for _ in 0..frames {
        s.step_frame().unwrap();
    }
    s.state().unwrap()
}

clothlab_tests::per_backend!(a_cloth_sliding_on_the_floor_slows_at_mu_k_g_and_stops_where_coulomb_says);

fn a_cloth_sliding_on_the_floor_slows_at_mu_k_g_and_stops_where_coulomb_says(name: &str) {
    // Every substep gravity adds g·dt into the floor and the contact removes it: the
    // tangential speed loses μk·g·dt, exactly, until it is below μs·g·dt and sticks. The
    // cloth moves as one piece (its springs unstretched), so after 0.25 s every particle
    // is at v0 − μk g t = 2 − 0.3 · 9.81 · 0.25 = 1.2643 m/s: 1e-4 m/s covers f32 rounding
    // of 240 substeps. It stops after v0/(μk g) = 0.680 s, having slid v0²/(2 μk g) −
    // v0·dt/2 (the substeps' sum: each moves by the speed after its own friction) =
    // 0.6786 m: 1 mm covers the last substep's fraction. At 1 s it is still, to 1e-6 m/s.
    let (v0, dt) = (2.0, SimParams::default().dt() as f64);
    if let Some(mut s) = backend(name, &on_the_floor(v0 as f32), &coulomb(MU_S, MU_K)) {
        let start = s.state().unwrap();
        let cx0 = mean(&start, |i| start.pos[i][0] as f64);
        let st = run(&mut *s, 15);
        let vx = mean(&st, |i| st.vel[i][0] as f64);
        let want = v0 - MU_K as f64 * G * 0.25;
        let st = run(&mut *s, 45);
        let (vx1, dx) = (mean(&st, |i| st.vel[i][0] as f64), mean(&st, |i| st.pos[i][0] as f64) - cx0);
        let slid = v0 * v0 / (2.0 * MU_K as f64 * G) - v0 * dt / 2.0;
        println!("{name:18} vx(0.25 s) {vx:.5} (Coulomb {want:.5}), vx(1 s) {vx1:.2e}, slid {dx:.4} m ({slid:.4})");
        assert!((vx - want).abs() <= 1e-4, "{name}: sliding at {vx} m/s after 0.25 s, Coulomb says {want}");
        assert!(vx1.abs() <= 1e-6, "{name}: still moving at {vx1} m/s after 1 s");
        assert!((dx - slid).abs() <= 1e-3, "{name}: slid {dx} m, Coulomb says {slid}");
    }
}

/// [`on_the_floor`] at rest, gravity tilted by `deg` about z: a slope of that angle.
fn slope(deg: f64, params: SimParams) -> (Scene, SimParams) {
    let (s, c) = deg.to_radians().sin_cos();
    let gravity = [(G * s) as f32, -(G * c) as f32, 0.0];
    (on_the_floor(0.0), SimParams { gravity, ..params })
}

clothlab_tests::per_backend!(a_slope_holds_the_cloth_below_tan_theta_mu_s_and_lets_it_slide_above);

fn a_slope_holds_the_cloth_below_tan_theta_mu_s_and_lets_it_slide_above(name: &str) {
    // 20°: tan θ = 0.364 < μs = 0.5. Each substep gravity's tangential g sin θ·dt is at
    // most μs times the normal g cos θ·dt the contact removes: the velocity stays 0 and
    // the position is moved back by what friction took, so the cloth does not creep — in
    // 0.5 s it moves less than 1e-5 m (rounding of 480 substeps' x + a − a at 0.1 m,
    // ulp 7e-9). The share model (friction 0.4) cannot hold it: it creeps at
    // 1.5 g sin θ·dt = 5 mm/s, more than 1 mm in 0.5 s.
    let (sc, p) = slope(20.0, coulomb(MU_S, MU_K));
    if let Some(mut s) = backend(name, &sc, &p) {
        let start = s.state().unwrap();
        let st = run(&mut *s, 30);
        let moved = (0..st.pos.len())
            .map(|i| (0..3).map(|k| (st.pos[i][k] - start.pos[i][k]).abs()).fold(0.0f32, f32::max))
            .fold(0.0f32, f32::max);
        println!("{name:18} 20° slope, μs 0.5: moved {moved:.2e} m in 0.5 s");
        assert!(moved <= 1e-5, "{name}: static friction let the cloth move {moved} m");
    }
    let (sc, p) = slope(20.0, still_air(0.4));
    let mut s = clothlab_cpu::CpuSolver::new(clothlab_cpu::Exec::Serial, sc, p).unwrap();
    let st = run(&mut s, 30);
    let crept = mean(&st, |i| st.pos[i][0] as f64);
    println!("share 0.4 on the 20° slope: crept {crept:.4} m in 0.5 s");
    assert!(crept > 1e-3, "the share model held the cloth on the slope ({crept} m)");
    // 30°: tan θ = 0.577 > μs. Sliding from the first substep at a = g (sin θ − μk cos θ)
    // = 2.357 m/s²: 1.1784 m/s after 0.5 s, to 1e-4 m/s (rounding, as on the floor).
    let want = G * (30f64.to_radians().sin() - MU_K as f64 * 30f64.to_radians().cos()) * 0.5;
    let (sc, p) = slope(30.0, coulomb(MU_S, MU_K));
    if let Some(mut s) = backend(name, &sc, &p) {
        let st = run(&mut *s, 30);
        let vx = mean(&st, |i| st.vel[i][0] as f64);
        println!("{name:18} 30° slope: vx {vx:.5} m/s (Coulomb {want:.5})");
        assert!((vx - want).abs() <= 1e-4, "{name}: sliding at {vx} m/s, Coulomb says {want}");
    }
}

#[test]
fn a_moving_table_drags_the_cloth_at_mu_k_g_until_it_carries_it() {
    // The table slides under the cloth: kinetic friction on the velocity relative to the
    // table accelerates it at μk g = 2.943 m/s² — 0.2943 m/s after 0.1 s, to 1e-4 m/s —
    // until it has the table's 0.5 m/s (at 0.170 s), then static friction holds it there:
    // 0.5 m/s at 0.5 s to 1e-5 relative (RK4: 1e-4, its stages evaluate the springs at
    // midpoints the contacts have not projected, so a few particles slip; measured
    // 0.499976). Every integrator but VBD (penalties) resolves the contact in the same
    // collide: Verlet runs it on every backend, the others on the CPU and the physics
    // tests' optimized recipe (`OPTIMIZED_ON`), as motion.rs's moving contacts do: each
    // integrator's recipe follows the CPU on every API (integrators.rs), and every API's
    // optimized recipe computes the CPU's bits with Coulomb's contacts on moving colliders
    // (below). Implicit Euler's CG on Vulkan and GL was 11 of this test's 26 s on lavapipe.
    let v = TABLE_V as f64;
    let early = MU_K as f64 * G * 0.1;
    for (integrator, carried) in
        [(Integrator::Verlet, 1e-5), (Integrator::Xpbd, 1e-5), (Integrator::Implicit, 1e-5), (Integrator::Rk4, 1e-4)]
    {
        let params = SimParams { integrator, ..coulomb(MU_S, MU_K) };
        let optimized = format!("{} optimized", clothlab_tests::OPTIMIZED_ON.name());
        let keep = |n: &str| integrator == Integrator::Verlet || n == "cpu" || n == optimized;
        for (name, mut s) in backends(&moving_table(0.0), &params, keep) {
            let st = run(&mut *s, 6);
            let vx = mean(&st, |i| st.vel[i][0] as f64);
            let st = run(&mut *s, 24);
            let vx1 = mean(&st, |i| st.vel[i][0] as f64);
            println!("{integrator:?} {name:18} vx(0.1 s) {vx:.5} (μk g t {early:.5}), vx(0.5 s) {vx1:.6}");
            assert!((vx - early).abs() <= 1e-4, "{integrator:?} on {name}: {vx} m/s after 0.1 s, Coulomb {early}");
            assert!((vx1 - v).abs() <= carried * v, "{integrator:?} on {name}: carried at {vx1}, the table {v}");
        }
    }
}

#[test]
fn vbd_slows_a_sliding_cloth_at_about_mu_k_g() {
    // VBD's contacts are penalties with the paper's smoothed Coulomb friction, μ = μk when
    // Coulomb's coefficients are given: the floor slide above slows at μk g within 1 % of
    // the speed lost (its λ is the penalty's force after the block's Newton step, not the
    // exact normal impulse; measured 0.06 %: 1.26472 for 1.26425 m/s), on the CPU and
    // each optimized recipe.
    let want = 2.0 - MU_K as f64 * G * 0.25;
    let params = SimParams { integrator: Integrator::Vbd, ..coulomb(MU_S, MU_K) };
    let keep = |n: &str| n == "cpu" || n.ends_with("optimized");
    for (name, mut s) in backends(&on_the_floor(2.0), &params, keep) {
        let st = run(&mut *s, 15);
        let vx = mean(&st, |i| st.vel[i][0] as f64);
        println!("VBD {name:18} vx(0.25 s) {vx:.5} (Coulomb {want:.5})");
        assert!((vx - want).abs() <= 0.01 * (2.0 - want), "VBD on {name}: {vx} m/s, Coulomb {want}");
    }
}

#[test]
fn coulomb_contacts_on_moving_colliders_are_the_cpus_bits_on_every_optimized_recipe() {
    // The moving table, a spinning sphere and the floor with Coulomb's coefficients: each
    // optimized recipe's kernels against their twins, and 12 frames rolled out bit for bit
    // on llvmpipe (the CPU's bits: the same operations in the same order).
    let mut sc = moving_table(0.0);
    sc.cloth.top_center = [0.0, 0.5 + 0.01 + 2e-3, -0.45];
    sc.cloth.size = 0.9;
    sc.spheres = vec![clothlab_core::Sphere::new([0.0, 0.55, 0.3], 0.2)];
    sc.motions.push((ColliderId::Sphere(0), Motion { spin: [0.0, 2.0, 1.0], ..Motion::default() }));
    sc.floor_y = Some(0.0);
    let params =
        SimParams { static_friction: 0.6, kinetic_friction: 0.4, strain_iterations: 1, ..SimParams::default() };
    assert_checks("coulomb", &clothlab_tests::optimized_kernel_checks(&sc, &params, 0xc0u64));
    clothlab_tests::assert_rollouts(clothlab_tests::optimized_rollout_solvers(&sc, &params), 12);
}

#[test]
fn bad_coulomb_coefficients_are_refused_in_one_line() {
    for (mu_s, mu_k, what) in [
        (0.2, 0.3, "must be ≤ static_friction"),
        (f32::NAN, 0.0, "finite"),
        (0.5, -0.1, "must be in"),
        (11.0, 0.0, "must be in"),
    ] {
        let e = coulomb(mu_s, mu_k).validate().unwrap_err().to_string();
        println!("μs {mu_s}, μk {mu_k}: {e}");
        assert!(e.contains(what) && !e.contains('\n'), "{e}");
        let r = clothlab_cpu::CpuSolver::new(clothlab_cpu::Exec::Serial, on_the_floor(0.0), coulomb(mu_s, mu_k));
        assert!(r.is_err(), "a solver took μs {mu_s}, μk {mu_k}");
    }
}
