//! Gradients through the cloth (`clothlab_cpu::grad`): the model is the solver's step,
//! and its adjoint is its derivative — against central finite differences of the f64
//! model and a closed form.

use clothlab_core::{SceneFile, Solver};
use clothlab_cpu::grad::{Model, PARAMS, Recording};
use clothlab_cpu::{CpuSolver, Exec};
use glam::DVec3;

/// An 8 × 8 cloth held at its top corners above a sphere and a floor: it falls onto the
/// sphere within the run (the contact's adjoint runs), no strain limit.
const DRAPE: &str = include_str!("drape.toml");

/// `frames` frames of `text` on the serial CPU solver, each frame's start recorded.
fn record(text: &str, frames: usize) -> (Recording, CpuSolver) {
    let f = SceneFile::parse(text, "grad").unwrap();
    let s = CpuSolver::new(Exec::Serial, f.scene.clone(), f.params.clone()).unwrap();
    record_from(s, &f, frames)
}

/// `frames` frames of `f` on `s` from its current state, each frame's start recorded.
fn record_from(mut s: CpuSolver, f: &SceneFile, frames: usize) -> (Recording, CpuSolver) {
    let w: Vec<f32> = s.state_ref().pos.iter().map(|x| x[3]).collect();
    let model = Model::new(&f.scene, s.topology(), &f.params, &w).unwrap();
    let mut rec = Recording::new(model);
    for _ in 0..frames {
        let st = s.state_ref().clone();
        rec.push(&st.pos, &st.vel);
        s.step_frame().unwrap();
    }
    (rec, s)
}

/// Deterministic weights in [-1, 1) (xorshift).
fn weights(n: usize, seed: u64) -> Vec<[f32; 3]> {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut next = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
    };
    (0..n).map(|_| [next(), next(), next()]).collect()
}

/// The loss Σ a·x + b·v of a replay's final state, and the trace of the switches the
/// replay took (`Model::take_trace`).
fn traced(rec: &Recording, a: &[[f32; 3]], b: &[[f32; 3]]) -> (f64, u64) {
    let (x, v) = rec.replay();
    let dot = |w: &[[f32; 3]], y: &[DVec3]| -> f64 {
        w.iter().zip(y).map(|(w, y)| DVec3::from(w.map(f64::from)).dot(*y)).sum()
    };
    (dot(a, &x) + dot(b, &v), rec.model().take_trace())
}

fn loss(rec: &Recording, a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    traced(rec, a, b).0
}

/// A finite difference of `loss` along a change `apply(rec, ±h)` on the smooth piece the
/// recording's own replay runs, and whether it is central: where a step switches a
/// contact or a limit (the strain limit's correction jumps where a spring passes its
/// limit: the loss is not continuous there; measured jumps of 1e-2 of the loss within
/// 1e-9 of a stiffness), h shrinks by 0.7 until both sides stay on the piece (a central
/// difference) or one does (a one-sided one), at most 60 times.
fn central(
    rec: &Recording,
    a: &[[f32; 3]],
    b: &[[f32; 3]],
    h: f64,
    apply: impl Fn(&mut Recording, f64),
) -> (f64, bool) {
    let (l0, trace) = traced(rec, a, b);
    let mut h = h;
    for _ in 0..60 {
        let (mut up, mut down) = (rec.clone(), rec.clone());
        apply(&mut up, h);
        apply(&mut down, -h);
        let ((lu, tu), (ld, td)) = (traced(&up, a, b), traced(&down, a, b));
        match (tu == trace, td == trace) {
            (true, true) => return ((lu - ld) / (2.0 * h), true),
            (true, false) => return ((lu - l0) / h, false),
            (false, true) => return ((l0 - ld) / h, false),
            _ => h *= 0.7,
        }
    }
    panic!("every step down to {h} switched a contact or a limit on both sides");
}

/// The drape with `extra` in its parameters (the strain limit's lines replace its
/// `strain_iterations = 0`).
fn drape_with(extra: &str) -> String {
    let text = format!("{DRAPE}{extra}\n");
    if extra.starts_with("strain") { text.replacen("strain_iterations = 0\n", "", 1) } else { text }
}

/// The drape's variants the model must compute as the solver does: both units of
/// stiffness (the springs' constants derived again in f64), the strain limit on, and
/// implicit Euler.
const VARIANTS: [&str; 4] = [
    "stiffness_units = \"fraction\"",
    "stiffness_units = \"physical\"",
    "strain_iterations = 2\nstrain_limit = 0.03",
    "integrator = \"implicit\"",
];

#[test]
fn the_f64_model_replays_the_solvers_run() {
    // 30 frames (240 substeps) of the drape on the f32 solver against the model's replay
    // in f64 from the first frame's state: the same step, so the same positions to f32's
    // rounding accumulated over the run (bound 1e-4 m; measured 1.1e-5 in fraction units),
    // in each variant (a spring constant derived otherwise than the solver's, or a strain
    // pass computed otherwise, would leave them millimetres apart). And the sphere was
    // touched: some particle ends on its grown surface.
    for extra in VARIANTS {
        let (rec, mut s) = record(&drape_with(extra), 30);
        let (x, _) = rec.replay();
        let st = s.state().unwrap();
        let most = x
            .iter()
            .zip(&st.pos)
            .map(|(a, b)| (*a - DVec3::new(b[0] as f64, b[1] as f64, b[2] as f64)).length())
            .fold(0.0, f64::max);
        let c = DVec3::new(0.0, 0.35, 0.05);
        let r = 0.25 + s.params().collision_margin as f64;
        let nearest = x.iter().map(|p| (*p - c).length() - r).fold(f64::INFINITY, f64::min);
        println!("{extra}: replay against the solver {most:.2e} m; nearest to the sphere {nearest:.2e} m");
        assert!(most < 1e-4, "{extra}: the model's step is not the solver's: {most} m apart");
        assert!(nearest.abs() < 1e-6, "{extra}: nothing rests on the sphere ({nearest} m)");
    }
}

#[test]
fn every_gradient_of_the_drape_is_its_finite_difference() {
    // In both units of stiffness: fractions of the stability limit (the default) and
    // physical moduli (whose gradients, and the mass's, are then not 0); and with two
    // strain passes a substep at a limit of 3 % (the springs over it pulled back, the
    // tethers holding the cloth to its corners: the limit's gradient is not 0).
    for extra in VARIANTS {
        drape_against_finite_differences(&drape_with(extra));
    }
}

fn drape_against_finite_differences(text: &str) {
    // The drape over 12 frames (96 substeps: the cloth lands on the sphere), the loss
    // Σ a·x + b·v of the final state with random weights. Each parameter's gradient, the
    // initial positions' and velocities' along three random directions, and two frames'
    // pins, against central differences of the f64 model (h 1e-6 of the value or of 1: truncation
    // ~1e-12, rounding ~1e-10 of the loss) of the recording's checkpoints in f64 (the
    // replay's own: `in_f64`): within 1e-5 relative, or of 1e-3 of the loss's scale where
    // the gradient is near 0 (the mass in fraction units: the springs scale with it).
    // The f32 run's own checkpoints give each gradient within 1e-2 of those (its
    // rounding moves where each frame's derivative is taken: measured up to 2e-3).
    // Implicit Euler's matrix has a kink where a spring passes its rest length (its
    // stiffness across the spring switches on as it stretches): the drape starts with
    // every spring there (and its falling middle keeps them there to f32's rounding for
    // frames), so a difference from it straddles the kink whichever its size. Its
    // free particles are moved at random by up to 1 cm first: the springs are off it,
    // and the trace shrinks the step off the ones that come near.
    let f = SceneFile::parse(text, "grad").unwrap();
    let mut s = CpuSolver::new(Exec::Serial, f.scene.clone(), f.params.clone()).unwrap();
    if text.contains("implicit") {
        let mut st = s.state_ref().clone();
        let np = st.pos.len();
        for (x, d) in st.pos.iter_mut().zip(weights(np, 99)) {
            if x[3] != 0.0 {
                (0..3).for_each(|c| x[c] += 0.01 * d[c]);
            }
        }
        s.set_state(&st).unwrap();
    }
    let (raw, s) = record_from(s, &f, 12);
    let rec = raw.in_f64();
    let np = s.state_ref().pos.len();
    let (a, b) = (weights(np, 1), weights(np, 2));
    let g = rec.backward(&a, &b);
    let g32 = raw.backward(&a, &b);
    let scale = loss(&rec, &a, &b).abs().max(1.0);
    // A one-sided difference's truncation is O(h): 1e-3 for it (measured to 2e-5).
    let check = |what: &str, got: f64, (want, both): (f64, bool)| {
        let err = (got - want).abs() / want.abs().max(1e-3 * scale);
        let bound = if both { 1e-5 } else { 1e-3 };
        println!(
            "{what:24} adjoint {got:+.6e}  finite difference {want:+.6e}  ({err:.1e}{})",
            if both { "" } else { ", one-sided" }
        );
        assert!(err < bound, "{what}: adjoint {got} against finite difference {want}");
    };
    let p0 = rec.model().params();
    for (k, name) in PARAMS.iter().enumerate() {
        let h = 1e-6 * p0[k].abs().max(1.0);
        let want = central(&rec, &a, &b, h, |r, d| r.model_mut().set_param(k, p0[k] + d));
        let got = g.params.iter().find(|(n, _)| n == name).unwrap().1;
        check(name, got, want);
        // (With the strain limit the f32 run and the f64 replay part where a spring passes
        // its limit in one and not the other, and then run different smooth pieces.)
        let got32 = g32.params.iter().find(|(n, _)| n == name).unwrap().1;
        let strained = text.contains("strain_iterations = 2");
        assert!(
            strained || (got32 - got).abs() <= 1e-2 * got.abs().max(1e-3 * scale),
            "{name}: the f32 run's {got32} against {got}"
        );
    }
    let pinned = g.pinned.clone();
    for seed in 0..3 {
        let dir = weights(np, 10 + seed);
        // Positions: the free particles at the start, the pinned ones in every frame.
        let got: f64 = g.positions.iter().zip(&dir).map(|(g, d)| (0..3).map(|c| g[c] * d[c] as f64).sum::<f64>()).sum();
        let want = central(&rec, &a, &b, 1e-6, |r, h| {
            for f in 0..r.frames() {
                let (x, _) = r.checkpoint_mut(f);
                for (i, p) in x.iter_mut().enumerate() {
                    if f == 0 || pinned.contains(&(i as u32)) {
                        *p += DVec3::from(dir[i].map(f64::from)) * h;
                    }
                }
            }
        });
        check(&format!("positions, direction {seed}"), got, want);
        let got: f64 =
            g.velocities.iter().zip(&dir).map(|(g, d)| (0..3).map(|c| g[c] * d[c] as f64).sum::<f64>()).sum();
        let want = central(&rec, &a, &b, 1e-6, |r, h| {
            let (_, v) = r.checkpoint_mut(0);
            for (i, p) in v.iter_mut().enumerate() {
                *p += DVec3::from(dir[i].map(f64::from)) * h;
            }
        });
        check(&format!("velocities, direction {seed}"), got, want);
    }
    // The pins of frames 3 and 9 alone (a controller's move in one frame).
    for f in [3, 9] {
        let dir = weights(pinned.len(), 20 + f as u64);
        let got: f64 = g.pins[f].iter().zip(&dir).map(|(g, d)| (0..3).map(|c| g[c] * d[c] as f64).sum::<f64>()).sum();
        let want = central(&rec, &a, &b, 1e-6, |r, h| {
            let (x, _) = r.checkpoint_mut(f);
            for (k, &i) in pinned.iter().enumerate() {
                x[i as usize] += DVec3::from(dir[k].map(f64::from)) * h;
            }
        });
        check(&format!("pins of frame {f}"), got, want);
    }
}

#[test]
fn free_fall_s_gradient_by_gravity_is_the_recurrence_s_closed_form() {
    // The free-fall scene (no pins, no floor, springs at rest: every particle the same
    // recurrence v' = r v + c g, x' = x + v' dt) with damping and drag on. Verlet:
    // r = 1 − damping − air_drag dt, c = dt; implicit Euler (its Newton step with the
    // springs at rest: m (1 + dt air_drag) Δv = dt m (g − air_drag v)): r = 1 − damping −
    // dt air_drag/(1 + dt air_drag), c = dt/(1 + dt air_drag). After N substeps
    // d y / d g_y = dt c Σ_{k=1..N} (1 − r^k)/(1 − r) for every particle, and
    // d y / d v₀ = dt Σ r^k. The loss: the mean height.
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/free-fall.toml")).unwrap();
    let text = text
        .replace("n = 32", "n = 6")
        .replace("air_drag = 0.0\ndamping = 0.0", "air_drag = 0.3\ndamping = 0.002\nstrain_iterations = 0");
    assert!(text.contains("air_drag = 0.3"), "scenes/free-fall.toml changed: the test's edit missed");
    for implicit in [false, true] {
        let text = if implicit {
            text.replace("strain_iterations = 0", "strain_iterations = 0\nintegrator = \"implicit\"")
        } else {
            text.clone()
        };
        let (rec, s) = record(&text, 10);
        let np = s.state_ref().pos.len();
        let a = vec![[0.0, 1.0 / np as f32, 0.0]; np];
        let g = rec.backward(&a, &vec![[0.0; 3]; np]);
        let p = s.params();
        let (dt, n, drag) = (p.dt() as f64, 10 * p.substeps as i32, p.air_drag as f64);
        let (r, c) = if implicit {
            (1.0 - p.damping as f64 - dt * drag / (1.0 + dt * drag), dt / (1.0 + dt * drag))
        } else {
            (1.0 - p.damping as f64 - drag * dt, dt)
        };
        let want_g: f64 = (1..=n).map(|k| dt * c * (1.0 - r.powi(k)) / (1.0 - r)).sum();
        let want_v: f64 = (1..=n).map(|k| dt * r.powi(k)).sum::<f64>() / np as f64;
        let got_g = g.params.iter().find(|(n, _)| *n == "gravity[1]").unwrap().1;
        println!(
            "implicit {implicit}: d mean y / d g_y {got_g:.9} against {want_g:.9}; d mean y / d v0_y {:.9e} against {want_v:.9e}",
            g.velocities[0][1]
        );
        // The springs stay at rest (every particle moves alike) but for the f32 run's
        // rounding of the checkpoints, which leaves them a few ulps off their rest
        // lengths: measured 7e-9 relative under either; bound 1e-6.
        assert!((got_g - want_g).abs() < 1e-6 * want_g.abs(), "implicit {implicit}: {got_g} against {want_g}");
        for v in &g.velocities {
            assert!(
                (v[1] - want_v).abs() < 1e-6 * want_v.abs() && v[0].abs() < 1e-6 * want_v.abs(),
                "implicit {implicit}: {v:?} against {want_v}"
            );
        }
    }
}

#[test]
fn what_has_no_adjoint_is_refused_in_one_line() {
    for (set, names) in [
        ("integrator = \"xpbd\"", "integrator"),
        ("wind = [1.0, 0.0, 0.0]", "wind"),
        ("static_friction = 0.5", "Coulomb"),
        ("self_collision = \"particles\"", "self-contact"),
    ] {
        let text = DRAPE.to_string() + set + "\n";
        let f = SceneFile::parse(&text, "refused").unwrap();
        let s = CpuSolver::new(Exec::Serial, f.scene.clone(), f.params.clone()).unwrap();
        let w: Vec<f32> = s.state_ref().pos.iter().map(|x| x[3]).collect();
        let e = Model::new(&f.scene, s.topology(), &f.params, &w).unwrap_err();
        assert!(e.contains(names) && !e.contains('\n'), "{set}: {e}");
    }
}

#[test]
fn a_held_particle_s_oscillation_has_the_recurrence_s_derivative_by_stiffness() {
    // A 3 × 3 cloth with every particle held but the middle one, nothing but its springs
    // acting (no gravity, drag or damping): moved 1 mm along the cloth, the middle one
    // oscillates along it on 2 structural springs (k_s) and 4 shear ones at 45° (k_sh/2
    // each) — with k = κ m/dt², s = ω²dt² = 2 κ_s + 2 κ_sh. Symplectic Euler's recurrence
    // then has cos θ = 1 − s/2 and x_N = A (cos Nθ − s/(2 sin θ) sin Nθ) exactly (a
    // linear oscillator to the springs' nonlinearity, of order (A/spacing)² = 1e-6 here, and
    // the f32 state's rounding, 1e-7 m of a 1 m spring against the 1 mm amplitude).
    // The gradient of x_N by κ_s and κ_sh against that closed form's derivative (2 ∂x_N/∂s
    // each): within 1e-3.
    let text = "[cloth]\nn = 3\nsize = 2.0\ntop_center = [0.0, 1.0, -1.0]\nacross = [1.0, 0.0, 0.0]\n\
                down = [0.0, 0.0, 1.0]\npinning = \"none\"\n[floor]\nenabled = false\n[params]\n\
                gravity = [0.0, 0.0, 0.0]\nair_drag = 0.0\ndamping = 0.0\nstrain_iterations = 0\n\
                structural_damping = 0.0\nshear_damping = 0.0\nbend_damping = 0.0\n";
    let f = SceneFile::parse(text, "oscillator").unwrap();
    let mut s = CpuSolver::new(Exec::Serial, f.scene.clone(), f.params.clone()).unwrap();
    let (amp, mid) = (1e-3f32, 4);
    let mut st = s.state_ref().clone();
    for (i, x) in st.pos.iter_mut().enumerate() {
        if i == mid {
            x[0] += amp;
        } else {
            x[3] = 0.0;
        }
    }
    s.set_state(&st).unwrap();
    let w: Vec<f32> = st.pos.iter().map(|x| x[3]).collect();
    let frames = 3;
    let mut rec = Recording::new(Model::new(&f.scene, s.topology(), &f.params, &w).unwrap());
    let x0 = st.pos[mid][0] as f64 - amp as f64;
    for _ in 0..frames {
        let st = s.state_ref().clone();
        rec.push(&st.pos, &st.vel);
        s.step_frame().unwrap();
    }
    let np = st.pos.len();
    let mut loss = vec![[0.0f32; 3]; np];
    loss[mid][0] = 1.0;
    let g = rec.backward(&loss, &vec![[0.0; 3]; np]);
    let n = (frames * f.params.substeps) as i32;
    let xn = |s: f64| {
        let theta = (1.0 - s / 2.0).acos();
        amp as f64 * ((n as f64 * theta).cos() - s / (2.0 * theta.sin()) * (n as f64 * theta).sin())
    };
    let s0 = 2.0 * (f.params.structural_stiffness + f.params.shear_stiffness) as f64;
    let d = (xn(s0 + 1e-7) - xn(s0 - 1e-7)) / 2e-7;
    let (x_end, _) = rec.replay();
    println!("x_N − x₀: replay {:.6e}, closed form {:.6e}; d/ds {d:.6e}", x_end[mid].x - x0, xn(s0));
    assert!((x_end[mid].x - x0 - xn(s0)).abs() < 1e-3 * amp as f64, "the model is not the oscillator");
    for name in ["structural_stiffness", "shear_stiffness"] {
        let got = g.params.iter().find(|(k, _)| *k == name).unwrap().1;
        println!("{name}: adjoint {got:.6e} against {:.6e}", 2.0 * d);
        assert!((got - 2.0 * d).abs() < 1e-3 * (2.0 * d).abs(), "{name}: {got} against {}", 2.0 * d);
    }
}

#[test]
fn internal_forces_move_no_gradient_of_the_mean() {
    // A free cloth (no pins, floor or colliders), its particles thrown at random so that
    // its springs and strain limit act, with damping and drag. Its mean moves as if no
    // internal force acted (equal and opposite: the momentum is kept), so for the mean
    // final x every particle's ∂x̄_N/∂x₀ᵢ is (1/N, 0, 0), its ∂x̄_N/∂v₀ᵢ is
    // (dt Σ_{k=1..N} r^k / N, 0, 0) with r = 1 − damping − air_drag·dt (a velocity only
    // decays by r a substep), and the springs' and the limit's parameters' gradients are 0
    // — to rounding (1e-9 of each). One particle's final x is moved by the others through
    // the springs (its gradient spreads over them: the test sees the springs act), and by
    // a common shift alike: Σᵢ ∂x_N/∂x₀ᵢ = (1, 0, 0). Under Verlet and implicit Euler
    // (whose Newton step's spring rows also cancel in the sum: r = 1 − damping −
    // dt air_drag/(1 + dt air_drag)).
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/free-fall.toml")).unwrap();
    let text = text
        .replace("n = 32", "n = 6")
        .replace("air_drag = 0.0\ndamping = 0.0", "air_drag = 0.3\ndamping = 0.002\nstrain_limit = 0.001");
    assert!(text.contains("strain_limit = 0.001"), "scenes/free-fall.toml changed: the test's edit missed");
    for implicit in [false, true] {
        let text = if implicit {
            text.replace("strain_limit = 0.001", "strain_limit = 0.001\nintegrator = \"implicit\"")
        } else {
            text.clone()
        };
        thrown_cloth_s_mean(&text, implicit);
    }
}

fn thrown_cloth_s_mean(text: &str, implicit: bool) {
    let f = SceneFile::parse(text, "thrown").unwrap();
    let mut s = CpuSolver::new(Exec::Serial, f.scene.clone(), f.params.clone()).unwrap();
    let mut st = s.state_ref().clone();
    for (v, w) in st.vel.iter_mut().zip(weights(st.pos.len(), 7)) {
        *v = [w[0], w[1], w[2], 0.0];
    }
    s.set_state(&st).unwrap();
    let w: Vec<f32> = st.pos.iter().map(|x| x[3]).collect();
    let mut rec = Recording::new(Model::new(&f.scene, s.topology(), &f.params, &w).unwrap());
    let frames = 6;
    for _ in 0..frames {
        let st = s.state_ref().clone();
        rec.push(&st.pos, &st.vel);
        s.step_frame().unwrap();
    }
    let rec = rec.in_f64();
    let np = st.pos.len();
    let p = &f.params;
    let (dt, n) = (p.dt() as f64, frames * p.substeps as i32);
    let drag = p.air_drag as f64;
    let r = 1.0 - p.damping as f64 - if implicit { dt * drag / (1.0 + dt * drag) } else { drag * dt };
    let decay: f64 = (1..=n).map(|k| dt * r.powi(k)).sum();
    // The loss's gradient goes in as f32: each particle's weight is 1/N to f32's rounding.
    let share = (1.0 / np as f32) as f64;
    let g = rec.backward(&vec![[share as f32, 0.0, 0.0]; np], &vec![[0.0; 3]; np]);
    let off = |rows: &[[f64; 3]], want: f64| {
        rows.iter().map(|r| (DVec3::from(*r) - DVec3::X * want).length()).fold(0.0, f64::max) / want
    };
    let (ox, ov) = (off(&g.positions, share), off(&g.velocities, decay * share));
    println!(
        "implicit {implicit}: the mean: each particle's gradient off its share by {ox:.1e} (positions), {ov:.1e} (velocities)"
    );
    assert!(ox < 1e-9 && ov < 1e-9, "{ox} {ov}");
    for name in ["structural_stiffness", "shear_stiffness", "bend_stiffness", "structural_damping", "strain_limit"] {
        let v = g.params.iter().find(|(k, _)| *k == name).unwrap().1;
        assert!(v.abs() < 1e-9, "{name}: {v}");
    }
    let mut one = vec![[0.0f32; 3]; np];
    one[0][0] = 1.0;
    let g = rec.backward(&one, &vec![[0.0; 3]; np]);
    let sum = g.positions.iter().fold(DVec3::ZERO, |a, r| a + DVec3::from(*r));
    let others = g.positions[1..].iter().map(|r| DVec3::from(*r).length()).fold(0.0, f64::max);
    let strain = g.params.iter().find(|(k, _)| *k == "strain_limit").unwrap().1;
    println!("particle 0: Σ ∂x/∂x₀ = {sum:?}; the largest other particle's {others:.3e}; ∂x/∂τ {strain:.3e}");
    assert!((sum - DVec3::X).length() < 1e-9, "{sum:?}");
    assert!(others > 1e-3, "particle 0 moved alone: the springs did not act ({others})");
    assert!(strain.abs() > 1e-6, "the strain limit never acted ({strain}): the test would hold less");
}
