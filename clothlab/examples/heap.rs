//! clothlab as a library: drop the heap scene on a backend named on the command line and
//! print the lowest point of the cloth as it falls.
//!
//! `cargo run --release -p clothlab --example heap -- vulkan` (default: cpu-par)

use clothlab::{Backend, Physics, SceneSource, Sim, SimOptions};

fn main() -> clothlab::Result<()> {
    let backend = Backend::parse(&std::env::args().nth(1).unwrap_or_else(|| "cpu-par".into()))?;
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/heap.toml");
    let mut sim = Sim::open(SimOptions {
        backend,
        physics: Physics { scene: SceneSource::File(scene.into()), integrator: None, set: vec!["substeps=16".into()] },
        ..Default::default()
    })?;
    println!("{} on {}: {} particles", sim.name(), sim.adapter(), sim.num_particles());
    for _ in 0..10 {
        sim.step(6)?;
        let lowest = sim.positions()?.iter().map(|p| p[1]).fold(f32::INFINITY, f32::min);
        println!("t = {:.2} s   lowest point {lowest:.3} m", sim.time());
    }
    Ok(())
}
