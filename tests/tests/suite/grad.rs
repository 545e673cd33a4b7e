//! Gradients on every GPU API (docs/gradients.md): a recording walked back by the adjoint
//! kernels (`clothlab_engine::grad::KernelWalk`) on each API against the same walk on the
//! CPU engine (their twins), and the twins' walk against the f64 model's.

use clothlab_core::{SceneFile, Solver};
use clothlab_cpu::grad::{Gradients, Model, Recording};
use clothlab_cpu::{CpuSolver, Exec};
use clothlab_engine::grad::KernelWalk;
use clothlab_engine::{CpuEngine, Variant};
use clothlab_tests::Api;

/// A 12 × 12 cloth held at its top corners above a sphere and a floor: it falls onto the
/// sphere within the run (the contact's adjoint runs), no strain limit.
const DRAPE: &str = r#"
[cloth]
n = 12
size = 0.8
top_center = [0.0, 0.7, -0.4]
across = [1.0, 0.0, 0.0]
down = [0.0, 0.0, 1.0]
pinning = "top-corners"

[floor]
y = 0.0

[[spheres]]
center = [0.0, 0.35, 0.05]
radius = 0.25

[params]
strain_iterations = 0
substeps = 8
friction = 0.3
"#;

/// `frames` frames of the drape on the serial CPU solver, recorded, and the state it
/// started from.
fn record(frames: usize) -> (SceneFile, Recording, clothlab_core::ClothState) {
    let f = SceneFile::parse(DRAPE, "grad").unwrap();
    let mut s = CpuSolver::new(Exec::Serial, f.scene.clone(), f.params.clone()).unwrap();
    let start = s.state_ref().clone();
    let w: Vec<f32> = start.pos.iter().map(|x| x[3]).collect();
    let mut rec = Recording::new(Model::new(&f.scene, s.topology(), &f.params, &w).unwrap());
    for _ in 0..frames {
        let st = s.state_ref().clone();
        rec.push(&st.pos, &st.vel);
        s.step_frame().unwrap();
    }
    (f, rec, start)
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

/// The largest difference of `got` from `want`: the initial state's gradients relative to
/// their largest magnitude, each parameter's relative to its own magnitude (or 1e-3 of
/// the largest parameter's, for one near 0), and the pins' relative to their largest.
fn worst(got: &Gradients, want: &Gradients) -> (f64, String) {
    let mut out = (0.0, String::new());
    let mut note = |e: f64, what: String| {
        if e > out.0 || e.is_nan() {
            out = (e, what);
        }
    };
    let rows = |g: &Gradients| -> Vec<(String, Vec<[f64; 3]>)> {
        let mut v =
            vec![("positions".to_string(), g.positions.clone()), ("velocities".to_string(), g.velocities.clone())];
        v.push(("pins".to_string(), g.pins.iter().flatten().copied().collect()));
        v
    };
    for ((name, a), (_, b)) in rows(got).into_iter().zip(rows(want)) {
        let scale = b.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        let diff = a.iter().flatten().zip(b.iter().flatten()).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        note(diff / scale.max(1e-30), name);
    }
    let big = want.params.iter().fold(0.0f64, |m, (_, x)| m.max(x.abs()));
    for ((name, a), (_, b)) in got.params.iter().zip(&want.params) {
        note((a - b).abs() / b.abs().max(1e-3 * big), name.to_string());
    }
    out
}

#[test]
fn the_adjoint_kernels_twins_walk_a_recording_as_the_f64_model_does() {
    // The twins compute the adjoint in f32 at the recorded f32 states; the model in f64.
    // Their difference is f32 rounding carried back through 96 substeps of a cloth on a
    // sphere (measured: see the assertion's message).
    let (f, rec, start) = record(12);
    let np = start.pos.len();
    let (xb, vb) = (weights(np, 1), weights(np, 2));
    let want = rec.backward(&xb, &vb);
    let s = CpuSolver::new(Exec::Serial, f.scene.clone(), f.params.clone()).unwrap();
    let mut engine = CpuEngine::new(Exec::Serial, f.scene.clone(), s.topology().clone());
    let mut walk = KernelWalk::new(&mut engine, &f.scene, &f.params, s.topology(), &start).unwrap();
    let got = rec.backward_by(&mut walk, &xb, &vb).unwrap();
    for ((name, a), (_, b)) in got.params.iter().zip(&want.params) {
        println!("{name:22} twins {a:+.6e} model {b:+.6e}");
    }
    let (e, what) = worst(&got, &want);
    println!("twins vs f64 model: worst {e:.2e} ({what})");
    assert!(e <= 2e-3, "the twins' gradients {e:.2e} off the f64 model's ({what})");
}

clothlab_tests::per_api!(every_api_s_gradients_are_the_twins_);

fn every_api_s_gradients_are_the_twins_(api: Api) {
    // The same walk on the API's kernels and on the CPU engine's twins: the kernels'
    // arithmetic against the twins' through 96 substeps' adjoints (adj_springs sums in
    // another order where FMA contracts: 1.8e-7 a call on lavapipe).
    let (f, rec, start) = record(12);
    let np = start.pos.len();
    let (xb, vb) = (weights(np, 3), weights(np, 4));
    let Some(mut gpu) = api.solver(Variant::OPTIMIZED, &f.scene, &f.params) else { return };
    let s = CpuSolver::new(Exec::Serial, f.scene.clone(), f.params.clone()).unwrap();
    let mut engine = CpuEngine::new(Exec::Serial, f.scene.clone(), s.topology().clone());
    let want = rec
        .backward_by(&mut KernelWalk::new(&mut engine, &f.scene, &f.params, s.topology(), &start).unwrap(), &xb, &vb)
        .unwrap();
    let got = rec
        .backward_by(&mut KernelWalk::new(gpu.runner(), &f.scene, &f.params, s.topology(), &start).unwrap(), &xb, &vb)
        .unwrap();
    let (e, what) = worst(&got, &want);
    println!("{} vs the twins: worst {e:.2e} ({what})", api.name());
    assert!(e <= 1e-4, "{}: gradients {e:.2e} off the twins' ({what})", api.name());
    clothlab_tests::assert_api_clean(&mut *gpu);
}

#[test]
fn a_gpu_walk_refuses_the_strain_limit_in_one_line() {
    let f = SceneFile::parse(&DRAPE.replace("strain_iterations = 0", "strain_iterations = 2"), "grad").unwrap();
    let s = CpuSolver::new(Exec::Serial, f.scene.clone(), f.params.clone()).unwrap();
    let mut engine = CpuEngine::new(Exec::Serial, f.scene.clone(), s.topology().clone());
    let e = KernelWalk::new(&mut engine, &f.scene, &f.params, s.topology(), s.state_ref()).err().unwrap().to_string();
    assert!(e.contains("strain") && !e.contains('\n'), "{e}");
}
