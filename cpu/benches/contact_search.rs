//! The contact between triangles' search, alone: `cargo bench -p clothlab-cpu --bench
//! contact_search`.
//!
//! The thin heap (n = 64) after 10 frames of its fall and the twist at Newton's settings (VBD, 10
//! substeps × 4 sweeps) after 30 frames of its turn are run on the CPU, then
//! `tri_contact::find_pairs` searches their state at the farthest reach a substep takes
//! plus the default margin (the thickness, two rest spacings and half a spacing: what a
//! search looks for while the cloth moves fast), on one thread and on rayon's.

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use clothlab_core::tri_contact::{MAX_REACH_SPACINGS, find_pairs};
use clothlab_core::{Integrator, SceneFile, Solver};
use clothlab_cpu::{CpuSolver, Exec};
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};

fn search(c: &mut Criterion) {
    let mut group = c.benchmark_group("contact_search");
    group.sample_size(20);
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    for (name, file, frames, vbd) in
        [("heap64", "thin-heap.toml", 10, false), ("twist", "twist-triangles.toml", 30, true)]
    {
        let f = SceneFile::load(&dir.join(file)).unwrap_or_else(|e| panic!("{e}"));
        let mut params = f.params.clone();
        if vbd {
            params.integrator = Integrator::Vbd;
            params.substeps = 10;
            params.vbd_iterations = 4;
        }
        let mut s = CpuSolver::new(Exec::Parallel, f.scene.clone(), params.clone()).unwrap();
        s.time_kernels = false;
        for _ in 0..frames {
            s.step_frame().unwrap();
        }
        let pos = s.state_ref().pos.clone();
        let triangles = s.topology().triangles.clone();
        let edges = clothlab_core::crossings::edges(&triangles);
        let spacing = f.scene.spacing();
        let reach = params.self_thickness + (MAX_REACH_SPACINGS + params.search_margin) * spacing;
        let (vt, ee) = find_pairs(&pos, &triangles, &edges, reach, false);
        eprintln!("{name}: {} vertices, {} pairs within {reach:.4} m", pos.len(), vt.len() + ee.len());
        for (exec, parallel) in [("serial", false), ("rayon", true)] {
            group.bench_with_input(BenchmarkId::new(exec, name), &name, |b, _| {
                b.iter(|| black_box(find_pairs(black_box(&pos), &triangles, &edges, reach, parallel)));
            });
        }
    }
    group.finish();
}

fn config() -> Criterion {
    Criterion::default().warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(4))
}

criterion_group! { name = benches; config = config(); targets = search }
criterion_main!(benches);
