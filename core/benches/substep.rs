//! Whole-substep cost of the CPU solvers: `cargo bench -p clothlab-core`.
//! Reports time per substep; divide by n² for ns per particle-substep (printed too).

use std::hint::black_box;

use clothlab_core::{CpuSolver, Exec, Scene, SimParams};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

fn substep(c: &mut Criterion) {
    let mut group = c.benchmark_group("substep");
    group.sample_size(20);
    let sizes: Vec<u32> = std::env::var("CLOTHLAB_BENCH_SIZES")
        .ok()
        .map(|s| s.split(',').filter_map(|x| x.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![128, 256, 512, 1024]);
    for &n in &sizes {
        group.throughput(Throughput::Elements(n as u64 * n as u64));
        for (name, exec) in [("serial", Exec::Serial), ("rayon", Exec::Parallel)] {
            let mut s = CpuSolver::new(exec, Scene::with_n(n), SimParams::default()).unwrap();
            s.time_kernels = false;
            // Let the cloth fall for a few frames so the measured step sees contacts and
            // stretched springs, not only the flat sheet.
            for _ in 0..8 * 16 {
                s.substep();
            }
            group.bench_with_input(BenchmarkId::new(name, n), &n, |b, _| b.iter(|| black_box(&mut s).substep()));
        }
    }
    group.finish();
}

criterion_group!(benches, substep);
criterion_main!(benches);
