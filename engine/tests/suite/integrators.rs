//! The integrators measured, not looked at: convergence orders and the period on a
//! spring–mass oscillator, free fall, implicit Euler's energy, the stability refusals, and
//! the fast CPU solvers against the CPU engine's recipes bit for bit. Everything runs the
//! recipes' twins, i.e. the commands the GPU backends record (tests/tests/suite/integrators.rs
//! runs the same integrators on both GPU APIs against these twins).

use std::f32::consts::TAU;

use clothlab_core::build;
use clothlab_core::grid::SpringSlot;
use clothlab_core::step_params::StepParams;
use clothlab_core::{Integrator, Scene, SimParams, Solver, StiffnessUnits};
use clothlab_cpu::{CpuSolver, Exec};
use clothlab_engine::cpu::start_buffers;
use clothlab_engine::recipe::{Command, Integration, recipe_for};
use clothlab_engine::{CpuEngine, HostBuffers, RecipeSolver, Variant};

/// Amplitude of the oscillator, m (it oscillates about the origin, where f32 is finest).
const A: f32 = 0.5;

/// A particle on a spring of rest length 1 to a pinned particle at x = −1, released at
/// x = A with no velocity: `x(t) = A cos(ωt)` with ω = 2π (period 1 s), stepped by the
/// CPU engine running `integrator`'s recipe with `per_period` substeps per period.
struct Oscillator {
    engine: CpuEngine,
    bufs: HostBuffers,
    p: StepParams,
    commands: Vec<Command>,
    k: f32,
}

impl Oscillator {
    fn new(integrator: Integrator, per_period: u32, gravity: [f32; 3], spring: bool) -> Self {
        let scene = Scene::with_n(2);
        let params = SimParams {
            gravity,
            air_drag: 0.0,
            damping: 0.0,
            strain_iterations: 0,
            integrator,
            // The grid's own springs are replaced by the one below.
            structural_stiffness: 0.0,
            shear_stiffness: 0.0,
            bend_stiffness: 0.0,
            structural_damping: 0.0,
            shear_damping: 0.0,
            bend_damping: 0.0,
            ..SimParams::default()
        };
        let (mut state, mut topo) = build(&scene, &params).unwrap();
        let m = params.particle_mass(2);
        let k = m * TAU * TAU;
        topo.slots.entries_mut().fill(SpringSlot::EMPTY);
        if spring {
            topo.slots.row_mut(1)[0] = SpringSlot { neighbor: 0, rest: 1.0, ks: k, kd: 0.0 };
        }
        state.pos = vec![[-1.0, 0.0, 0.0, 0.0], [A, 0.0, 0.0, 1.0], [5.0, 5.0, 5.0, 0.0], [6.0, 5.0, 5.0, 0.0]];
        let mut p = StepParams::new(&params, &scene, None);
        p.dt = 1.0 / per_period as f32;
        p.floor_y = -1e4;
        (p.num_spheres, p.num_boxes) = (0, 0);
        state.vel = vec![[0.0; 4]; 4];
        if integrator == Integrator::Verlet {
            // Verlet is a two-step method: its history is x(−dt), whose velocity form is
            // the velocity at −dt/2, (x₀ − x(−dt))/dt — not the velocity at 0 (a
            // first-order start, which symplectic Euler, the same recurrence, takes).
            if spring {
                state.vel[1][0] = (A - A * (TAU * p.dt).cos()) / p.dt;
            } else {
                state.vel[1][1] = -0.5 * gravity[1] * p.dt;
            }
        }
        let bufs = start_buffers(Exec::Serial, &p, &topo, &state);
        let how =
            Integration { integrator, cg_iterations: 16, xpbd_iterations: 1, vbd_iterations: 8, ..Integration::VERLET };
        let commands = recipe_for(&Variant::OPTIMIZED, 0, how, &topo);
        let engine = CpuEngine::new(Exec::Serial, scene, topo);
        Self { engine, bufs, p, commands, k }
    }

    fn step(&mut self) {
        self.engine.run(&self.commands, &self.p, 0, &mut self.bufs);
    }

    fn x(&self) -> [f32; 4] {
        self.bufs.pos[1]
    }

    /// Kinetic plus spring energy, J.
    fn energy(&self) -> f64 {
        let x = self.bufs.pos[1];
        let v = self.bufs.vel[1][0] as f64;
        let m = self.p.particle_mass as f64;
        0.5 * m * v * v + 0.5 * self.k as f64 * (x[0] as f64).powi(2)
    }
}

/// The global error: max |xₙ − A cos(2π tₙ)| over 1.25 periods (amplitude errors show at
/// the peaks, phase errors at the crossings) with `per_period` substeps per period.
fn error(integrator: Integrator, per_period: u32) -> f64 {
    let mut o = Oscillator::new(integrator, per_period, [0.0; 3], true);
    let mut worst = 0.0f64;
    for s in 1..=per_period * 5 / 4 {
        o.step();
        let t = s as f64 / per_period as f64;
        worst = worst.max((o.x()[0] as f64 - A as f64 * (TAU as f64 * t).cos()).abs());
    }
    worst
}

#[test]
fn every_integrator_converges_at_its_order_on_a_spring_mass_oscillator() {
    // (integrator, expected order, substeps per period of the coarse run; the fine run
    // has twice as many). The steps are where each method is in its asymptotic range and
    // its error (≥ 1e-5 m) is far above f32 rounding (≈ 1e-7 m per substep here).
    let cases = [
        (Integrator::Euler, 1.0, 512),
        (Integrator::SymplecticEuler, 1.0, 256),
        (Integrator::Rk2, 2.0, 64),
        (Integrator::Verlet, 2.0, 64),
        (Integrator::Rk4, 4.0, 16),
        (Integrator::Implicit, 1.0, 512),
        // One vertex on one spring along x: its block is the whole system and its energy
        // quadratic along the spring, so each Newton step solves it: implicit Euler's
        // order.
        (Integrator::Vbd, 1.0, 512),
    ];
    for (integrator, want, n) in cases {
        let (coarse, fine) = (error(integrator, n), error(integrator, 2 * n));
        let order = (coarse / fine).log2();
        println!("{:17} error {coarse:.3e} at {n}, {fine:.3e} at {}: order {order:.2}", integrator.name(), 2 * n);
        assert!(
            (order - want).abs() <= 0.2,
            "{}: measured order {order:.2}, expected {want} ± 0.2 (errors {coarse:.3e}, {fine:.3e})",
            integrator.name()
        );
    }
}

/// The mean period over `periods` periods, from the upward zero crossings (linearly
/// interpolated between substeps).
fn period(integrator: Integrator, per_period: u32, periods: u32) -> f64 {
    let mut o = Oscillator::new(integrator, per_period, [0.0; 3], true);
    let dt = 1.0 / per_period as f64;
    let mut crossings = Vec::new();
    let mut last = o.x()[0] as f64;
    for s in 1..=per_period * periods {
        o.step();
        let x = o.x()[0] as f64;
        if last < 0.0 && x >= 0.0 {
            crossings.push((s as f64 - 1.0 + -last / (x - last)) * dt);
        }
        last = x;
    }
    (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64
}

#[test]
fn the_second_order_methods_keep_the_period_within_one_percent_at_64_steps() {
    // Verlet's period error is (ω dt)²/24 ≈ 0.04 %, RK4's far less; the midpoint method's
    // is (ω dt)²/24 too (its amplitude grows, its phase does not drift faster).
    for integrator in [Integrator::Verlet, Integrator::Rk2, Integrator::Rk4] {
        let t = period(integrator, 64, 10);
        println!("{:8} period {t:.5} s (exact 1)", integrator.name());
        assert!((t - 1.0).abs() < 0.01, "{}: period {t} s, want 1 s ± 1 %", integrator.name());
    }
    // A first-order method at the same steps misses it (so the check can fail): explicit
    // Euler's amplitude grows 1.85-fold per period, and its zero crossings drift with it
    // (measured: 1.28 s).
    let euler = period(Integrator::Euler, 64, 10);
    println!("euler    period {euler:.5} s");
    assert!((euler - 1.0).abs() > 0.01, "explicit Euler's period {euler} s within 1 %");
}

#[test]
fn free_fall_is_exact_to_rounding_for_verlet_and_symplectic_eulers_velocity() {
    // Verlet integrates a constant acceleration exactly: y(t) = −g t²/2 at every substep,
    // its velocity the half step's, g (t − dt/2). Symplectic Euler (the same recurrence,
    // started from the velocity at 0) has the exact velocity (v = −g t) and its position
    // carries the known first-order bias: y_N = −g dt² N(N+1)/2, i.e. −g t²/2 − g t dt/2.
    // One second in 100 substeps.
    let g = -9.81f32;
    for integrator in [Integrator::Verlet, Integrator::SymplecticEuler] {
        let mut o = Oscillator::new(integrator, 100, [0.0, g, 0.0], false);
        let dt = o.p.dt as f64;
        let mut worst = (0.0f64, 0.0f64);
        for s in 1..=100u32 {
            o.step();
            let t = s as f64 * dt;
            let (y, v) = (o.x()[1] as f64, o.bufs.vel[1][1] as f64);
            let (want_y, want_v) = match integrator {
                Integrator::Verlet => (0.5 * g as f64 * t * t, g as f64 * dt * (s as f64 - 0.5)),
                _ => (0.5 * g as f64 * dt * dt * (s * (s + 1)) as f64, g as f64 * dt * s as f64),
            };
            // In units of the rounding allowed: each substep rounds y by up to an ulp
            // (2⁻²³|y|) and v by up to an ulp of v, which the positions carry on: at most
            // s ulps of y, bounded here by s^1.5 as before the state kept velocities.
            worst.0 = worst.0.max((y - want_y).abs() / ((s as f64).powf(1.5) * y.abs() * 2f64.powi(-23)));
            worst.1 = worst.1.max((v - want_v).abs() / want_v.abs());
        }
        println!(
            "{:17} worst position error {:.2} of the rounding bound, velocity relative error {:.2e}",
            integrator.name(),
            worst.0,
            worst.1
        );
        // Within the accumulated rounding (5e-4 m at the end; a first-order bias, g t dt / 2
        // = 0.05 m, would be 100 times over it). The velocity is a sum of s increments
        // g·dt, each rounded to half an ulp of v: relative error ≤ s·2⁻²⁴ = 6e-6 at s = 100
        // (as a difference of two positions, before the state kept it, it was 5e-3).
        assert!(worst.0 <= 1.0, "{}: position off by {:.2} of the rounding bound", integrator.name(), worst.0);
        assert!(worst.1 < 1e-5, "{}: velocity off by {:.2e}", integrator.name(), worst.1);
    }
}

#[test]
fn implicit_euler_and_vbd_never_gain_energy_at_any_step_and_explicit_euler_does() {
    for (integrator, per_period) in
        [64u32, 6, 1].into_iter().flat_map(|n| [(Integrator::Implicit, n), (Integrator::Vbd, n)])
    {
        // ω dt = 0.1, 1 and 6.3: explicit methods are unstable beyond 2.
        let mut o = Oscillator::new(integrator, per_period, [0.0; 3], true);
        let e0 = o.energy();
        let mut e = e0;
        for s in 0..200 {
            o.step();
            let next = o.energy();
            // Rounding only: 1e-9 of the initial energy (f32 positions near the origin).
            let name = integrator.name();
            assert!(next <= e + 1e-9 * e0, "{name}, {per_period}/period, substep {s}: energy {e} → {next}");
            e = next;
        }
        println!("{:8} {per_period:3}/period: energy {e0:.3e} → {e:.3e} J after 200 substeps", integrator.name());
        assert!(e < e0, "{} damps", integrator.name());
    }
    let mut o = Oscillator::new(Integrator::Euler, 64, [0.0; 3], true);
    let e0 = o.energy();
    for _ in 0..64 {
        o.step();
    }
    println!("euler     64/period: energy {e0:.3e} → {:.3e} J after one period", o.energy());
    assert!(o.energy() > 1.5 * e0, "explicit Euler gains (1 + (ω dt)²)^64 ≈ 1.85 per period");
}

#[test]
fn explicit_integrators_refuse_what_they_cannot_integrate_and_name_the_substeps() {
    let h = |n: u32| 2.0 / (n - 1) as f32;
    let with = |integrator, units| SimParams { integrator, stiffness_units: units, ..SimParams::default() };
    // Fraction mode: the defaults (Σκ 0.65, Σζ 0.07) are Verlet's and RK4's, not Euler's
    // or the midpoint method's (some mode grows at every dt).
    for i in [Integrator::Verlet, Integrator::SymplecticEuler, Integrator::Rk4, Integrator::Implicit, Integrator::Xpbd]
    {
        assert_eq!(with(i, StiffnessUnits::Fraction).validate_for(128, h(128)), Ok(()), "{}", i.name());
    }
    for i in [Integrator::Euler, Integrator::Rk2] {
        let e = with(i, StiffnessUnits::Fraction).validate_for(128, h(128)).unwrap_err();
        assert_eq!(e.field, "integrator", "{e}");
        assert!(e.reason.contains("implicit"), "{e}");
    }
    // Physical mode at n = 128: Verlet, RK4 and Euler need more substeps than 16 (each
    // names how many, and that many pass: the state in (x, v) integrates any count up to
    // 1024). Implicit, XPBD and VBD take any dt.
    for i in [Integrator::Verlet, Integrator::Rk4, Integrator::Euler] {
        let p = with(i, StiffnessUnits::Physical);
        let e = p.validate_for(128, h(128)).unwrap_err();
        let need: u32 = e.reason.split("substeps ≥ ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
        println!("{:8} at n = 128 needs {need} substeps per 1/60 s frame", i.name());
        assert_eq!(SimParams { substeps: need, ..p.clone() }.validate_for(128, h(128)), Ok(()), "{}", i.name());
    }
    for i in [Integrator::Implicit, Integrator::Xpbd, Integrator::Vbd] {
        assert_eq!(with(i, StiffnessUnits::Physical).validate_for(512, h(512)), Ok(()), "{}", i.name());
    }
}

fn bits(v: &[[f32; 4]]) -> Vec<[u32; 4]> {
    v.iter().map(|p| p.map(f32::to_bits)).collect()
}

#[test]
fn the_fast_cpu_solvers_compute_the_bits_of_every_integrators_recipe() {
    // n = 37 (rows not a multiple of the SIMD lanes), wind, two strain passes; soft
    // springs with heavy damping so that explicit Euler (which needs Σζ > Σκ) runs too.
    for integrator in Integrator::ALL {
        let params = SimParams {
            wind: [2.0, 0.0, 1.0],
            strain_iterations: 2,
            integrator,
            cg_iterations: 8,
            xpbd_iterations: 2,
            ..SimParams::default()
        }
        .with_soft_springs();
        let scene = Scene::with_n(37);
        let mut engine = RecipeSolver::new(Exec::Serial, Variant::OPTIMIZED, scene.clone(), params.clone()).unwrap();
        let mut serial = CpuSolver::new(Exec::Serial, scene.clone(), params.clone()).unwrap();
        let mut rayon = CpuSolver::new(Exec::Parallel, scene, params.clone()).unwrap();
        for frame in 0..3 {
            engine.step_frame().unwrap();
            serial.step_frame().unwrap();
            rayon.step_frame().unwrap();
            let e = engine.state().unwrap();
            assert!(e.pos.iter().flatten().all(|v| v.is_finite()), "{}: NaN", integrator.name());
            for s in [&serial, &rayon] {
                let st = s.state_ref();
                for (name, a, b) in [("pos", &e.pos, &st.pos), ("vel", &e.vel, &st.vel)] {
                    assert!(
                        bits(a) == bits(b),
                        "{}, frame {frame}: {} {name} differs from the CPU engine",
                        integrator.name(),
                        s.name()
                    );
                }
            }
        }
    }
}
