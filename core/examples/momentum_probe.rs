//! Horizontal momentum of a cloth dropped onto a frictionless floor (no drag, damping or
//! wind): nothing outside the cloth pushes it sideways, so its centre of mass must not
//! move in x or z. Prints the centre's sideways drift and velocity after the given frames
//! with each internal correction on alone and all together, on the CPU solver.
//!
//! `cargo run --release -p clothlab-core --example momentum_probe -- 32 40`
use clothlab_core::params::Integrator;
use clothlab_core::scene::Pinning;
use clothlab_core::{CpuSolver, Exec, Scene, SimParams, Solver};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: u32 = args.get(1).map_or(32, |s| s.parse().expect("n"));
    let frames: u32 = args.get(2).map_or(40, |s| s.parse().expect("frames"));
    let mut scene = Scene::with_n(n);
    scene.cloth.size = 1.0;
    scene.cloth.top_center = [0.0, 1.25, 0.0];
    scene.cloth.down = [0.0, -0.9798, 0.2];
    scene.cloth.pinning = Pinning::None;
    scene.spheres.clear();
    scene.boxes.clear();
    scene.floor_y = Some(0.0);
    let base = SimParams { friction: 0.0, damping: 0.0, air_drag: 0.0, strain_iterations: 0, ..SimParams::default() };
    let cases: Vec<(&str, SimParams)> = vec![
        ("springs", base.clone()),
        ("strain", SimParams { strain_iterations: 2, ..base.clone() }),
        ("self", SimParams { self_collision: true, self_thickness: 0.02, ..base.clone() }),
        ("xpbd", SimParams { integrator: Integrator::Xpbd, ..base.clone() }),
        (
            "xpbd+all",
            SimParams {
                integrator: Integrator::Xpbd,
                strain_iterations: 2,
                self_collision: true,
                self_thickness: 0.02,
                ..base.clone()
            },
        ),
        ("all", SimParams { strain_iterations: 2, self_collision: true, self_thickness: 0.02, ..base.clone() }),
        ("friction", SimParams { friction: 0.6, strain_iterations: 2, self_collision: true, ..base.clone() }),
    ];
    for (name, p) in cases {
        let mut s = CpuSolver::new(Exec::Serial, scene.clone(), p).expect("solver");
        let com = |st: &clothlab_core::ClothState| {
            let (mut x, mut z, mut vx, mut vz, mut m) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
            for (p, v) in st.pos.iter().zip(&st.vel) {
                let w = 1.0 / p[3].max(1e-30) as f64;
                x += w * p[0] as f64;
                z += w * p[2] as f64;
                vx += w * v[0] as f64;
                vz += w * v[2] as f64;
                m += w;
            }
            (x / m, z / m, vx / m, vz / m)
        };
        let s0 = s.state().unwrap();
        let c0 = com(&s0);
        let rms0 = 0.0;
        for _ in 0..frames {
            s.step_frame().unwrap();
        }
        let st = s.state().unwrap();
        let c1 = com(&st);
        let rms = (st.vel.iter().map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) as f64).sum::<f64>()
            / st.vel.len() as f64)
            .sqrt();
        let _ = rms0;
        println!(
            "{name:9} drift x {:+.2e} z {:+.2e} m, v x {:+.2e} z {:+.2e} m/s (rms speed {rms:.3})",
            c1.0 - c0.0,
            c1.1 - c0.1,
            c1.2,
            c1.3
        );
    }
}
