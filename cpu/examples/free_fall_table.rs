//! The free-fall table of issue 31: a free 24 × 24 cloth (no pins, floor, drag, damping or
//! wind), tilted, its top edge at 3.7 m (or the height given), falls for 30 frames; the
//! table gives its centre of mass's drop against each integrator's own recurrence in exact
//! arithmetic (RK2 and RK4: ½ g t²), in % of the drop, at each substep count.
//!
//! `cargo run --release -p clothlab-cpu --example free_fall_table [-- HEIGHT]`. The CPU
//! solver computes the optimized GPU kernels' bits, so the table holds for them too.

use clothlab_core::scene::Pinning;
use clothlab_core::{Integrator, Scene, SimParams, Solver};
use clothlab_cpu::{CpuSolver, Exec};

fn main() {
    let height: f32 = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(3.7);
    let mut scene = Scene::with_n(24);
    scene.cloth.pinning = Pinning::None;
    scene.cloth.top_center = [0.0, height, -0.5];
    scene.cloth.down = [0.0, -0.6, 0.8];
    scene.floor_y = None;
    scene.spheres.clear();
    let frames = 30u32;
    let integrators = [Integrator::Verlet, Integrator::Xpbd, Integrator::Implicit, Integrator::Rk4];
    print!("| substeps |");
    for i in integrators {
        print!(" {} |", i.name());
    }
    println!("\n|---:|{}", "---:|".repeat(integrators.len()));
    for substeps in [8u32, 16, 32, 64, 128, 256, 512, 1024] {
        print!("| {substeps} |");
        for integrator in integrators {
            let params = SimParams { integrator, substeps, air_drag: 0.0, damping: 0.0, ..SimParams::default() };
            let mut s = CpuSolver::new(Exec::Parallel, scene.clone(), params.clone()).expect("a valid scene");
            let y = |s: &CpuSolver| s.state_ref().pos.iter().map(|p| p[1] as f64).sum::<f64>() / 576.0;
            let y0 = y(&s);
            for _ in 0..frames {
                s.step_frame().expect("a step");
            }
            let k = (frames * substeps) as f64;
            let (g, dt) = (-params.gravity[1] as f64, params.dt() as f64);
            let want = match integrator {
                Integrator::Rk4 | Integrator::Rk2 => 0.5 * g * (k * dt).powi(2),
                Integrator::Euler => g * dt * dt * k * (k - 1.0) / 2.0,
                _ => g * dt * dt * k * (k + 1.0) / 2.0,
            };
            print!(" {:+.4} % |", ((y0 - y(&s)) - want) / want * 100.0);
        }
        println!();
    }
}
