//! The route of docs/contact.md tried on the CPU around the solver, before it is a stage of
//! the step: a scene stepped with the particle contact off, and after every substep each
//! vertex's motion clamped to its bound (found at the substep's start) and a pass of
//! `tri_contact::separate`, clamped too; the velocity takes the change, as the strain
//! limit's does. Prints the crossings every 10 frames and the time a substep's contact
//! takes.
//!
//!   cargo run --release -p clothlab-core --example triangle_contact_probe -- scenes/stack.toml 150

use std::time::Instant;

use clothlab_core::tri_contact::{motion_bounds, separate};
use clothlab_core::{CpuSolver, Exec, SceneFile, SimParams, Solver, crossings};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).map(String::as_str).unwrap_or("scenes/stack.toml");
    let frames: u32 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(150);
    let f = SceneFile::load(std::path::Path::new(path)).expect("a scene file");
    let thickness = f.params.self_thickness;
    let params = SimParams { self_collision: false, ..f.params };
    let (dt, substeps_per_frame) = (params.dt(), params.substeps);
    let mut s = CpuSolver::new(Exec::Parallel, f.scene, params).unwrap();
    let triangles = s.topology().triangles.clone();
    let (mut contact_ns, mut substeps) = (0.0, 0u64);
    for frame in 1..=frames {
        for _ in 0..substeps_per_frame {
            let x0 = s.state_ref().pos.clone();
            s.substep();
            let t = Instant::now();
            let mut state = s.state_ref().clone();
            let bounds = motion_bounds(&x0, &triangles, thickness);
            let clamp = |x: &mut [[f32; 4]]| {
                for (k, x) in x.iter_mut().enumerate() {
                    let d = [x[0] - x0[k][0], x[1] - x0[k][1], x[2] - x0[k][2]];
                    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    if len > bounds[k] {
                        let q = bounds[k] / len;
                        for c in 0..3 {
                            x[c] = x0[k][c] + d[c] * q;
                        }
                    }
                }
            };
            let x1 = state.pos.clone();
            let mut x = x1.clone();
            clamp(&mut x);
            let inv: Vec<f32> = x.iter().map(|p| p[3]).collect();
            let mut out = x.clone();
            separate(&x, &triangles, &inv, thickness, &mut out);
            clamp(&mut out);
            for (k, v) in state.vel.iter_mut().enumerate() {
                for c in 0..3 {
                    v[c] += (out[k][c] - x1[k][c]) / dt;
                }
            }
            state.pos = out;
            s.set_state(&state).unwrap();
            contact_ns += t.elapsed().as_nanos() as f64;
            substeps += 1;
        }
        if frame % 10 == 0 || frame == frames {
            let c = crossings::count(&s.state_ref().pos, &triangles);
            let lowest = s.state_ref().pos.iter().map(|p| p[1]).fold(f32::INFINITY, f32::min);
            println!(
                "frame {frame:4}: {} crossings, lowest {lowest:.4} m, contact {:.1} ms a substep",
                c.pairs,
                contact_ns / substeps as f64 / 1e6
            );
        }
    }
}
