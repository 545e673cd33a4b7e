//! The contact between triangles' search, alone: `cargo bench -p clothlab-core --bench
//! contact_search`.
//!
//! The thin heap (n = 64) as it lands and the twist at Newton's settings (VBD, 10
//! substeps × 4 sweeps) halfway through its turn are run on the CPU, then
//! `tri_contact::find_pairs_within` searches their state as `Contact::begin` does: each
//! vertex's reach from its speed plus the default margin (half a rest spacing), on one
//! thread and on rayon's. It prints how many pairs that finds against one reach for every
//! vertex (the fastest's, as the contact searched before each vertex had its own).

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use clothlab_core::tri_contact::{Contact, Reach, find_pairs_within};
use clothlab_core::{CpuSolver, Exec, Integrator, SceneFile, Solver};
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};

fn search(c: &mut Criterion) {
    let mut group = c.benchmark_group("contact_search");
    group.sample_size(20);
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    for (name, file, frames, vbd) in
        [("heap64", "thin-heap.toml", 30, false), ("twist", "twist-triangles.toml", 30, true)]
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
        let (pos, vel) = (s.state_ref().pos.clone(), s.state_ref().vel.clone());
        let triangles = s.topology().triangles.clone();
        let edges = clothlab_core::crossings::edges(&triangles);
        let spacing = f.scene.spacing();
        let mut own = Vec::new();
        let most =
            Contact::reaches(&pos, &vel, spacing, params.dt(), params.gravity, params.self_thickness, 1, &mut own);
        let m = params.search_margin * spacing;
        let far: Vec<f32> = own.iter().map(|r| r + m).collect();
        let reach = Reach::Each(&far, most + m);
        let count = |r: Reach| {
            let (vt, ee) = find_pairs_within(&pos, &triangles, &edges, r, true);
            vt.len() + ee.len()
        };
        eprintln!(
            "{name}: {} vertices, reaches {:.4}-{most:.4} m and the margin {m:.4}: {} pairs; {} within the largest",
            pos.len(),
            own.iter().copied().fold(f32::INFINITY, f32::min),
            count(reach),
            count(Reach::All(most + m)),
        );
        for (exec, parallel) in [("serial", false), ("rayon", true)] {
            group.bench_with_input(BenchmarkId::new(exec, name), &name, |b, _| {
                b.iter(|| black_box(find_pairs_within(black_box(&pos), &triangles, &edges, reach, parallel)));
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
