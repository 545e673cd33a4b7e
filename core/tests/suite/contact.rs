//! Contact between triangles: the motion bounds keep a layered state layered.

use std::path::Path;

use clothlab_core::crossings;
use clothlab_core::tri_contact::motion_bounds;
use clothlab_core::{CpuSolver, Exec, SceneFile, Solver};

/// A deterministic direction of length below 1 for vertex `k` in round `r` (xorshift).
fn jitter(k: usize, r: u32) -> [f32; 3] {
    let mut s = (k as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (r as u64 + 1).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    let mut next = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
    };
    let v = [next(), next(), next()];
    let len = v.iter().map(|c| c * c).sum::<f32>().sqrt().max(1e-6);
    let u = (next() + 1.0) * 0.5;
    v.map(|c| c / len * u * 0.999)
}

#[test]
fn vertices_moved_within_their_bounds_never_cross_and_three_times_as_far_do() {
    // The five sheets of scenes/stack.toml, run on the CPU to frame 14: piled on the sphere,
    // layers millimetres apart, not yet crossed (the particle contact lets the first
    // crossing through at frame 16). Then 12 rounds of every vertex moved in a random
    // direction by up to its bound (reach: one spacing, 3.2 cm), bounds found again each
    // round: still no crossing. The same moves at three times the bounds cross (so the
    // count can fail).
    let f = SceneFile::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/stack.toml")).unwrap();
    let mut s = CpuSolver::new(Exec::Parallel, f.scene, f.params).unwrap();
    for _ in 0..14 {
        s.step_frame().unwrap();
    }
    let triangles = s.topology().triangles.clone();
    let start = s.state_ref().pos.clone();
    assert_eq!(crossings::count(&start, &triangles).pairs, 0, "the pile crossed before the test began");
    let reach = 1.0 / 31.0;
    let run = |scale: f32, rounds: u32| {
        let mut pos = start.clone();
        let mut most = 0;
        for r in 0..rounds {
            let bounds = motion_bounds(&pos, &triangles, reach);
            for (k, x) in pos.iter_mut().enumerate() {
                let d = jitter(k, r);
                for c in 0..3 {
                    x[c] += d[c] * bounds[k] * scale;
                }
            }
            most = most.max(crossings::count(&pos, &triangles).pairs);
        }
        most
    };
    assert_eq!(run(1.0, 12), 0, "a move within the bounds crossed");
    let over = run(3.0, 3);
    println!("moves of three times the bounds: at most {over} crossings in a round");
    assert!(over > 0, "moves beyond the bounds should cross somewhere in the pile");
}
