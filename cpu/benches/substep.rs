//! Whole-substep cost of the CPU solvers: `cargo bench -p clothlab-cpu`.
//!
//! Per grid size, the serial and rayon solvers as they run (the fused sweep at the
//! instruction set chosen at run time) and kernel by kernel (`*-kernels`, the path the
//! fused sweep replaced), each timed over whole frames and reported per substep (divide by
//! n² for ns per particle-substep). `CLOTHLAB_CPU_SIMD` picks a narrower instruction set;
//! `CLOTHLAB_BENCH_SIZES=512` measures one size.

use std::hint::black_box;
use std::time::{Duration, Instant};

use clothlab_core::{Scene, SimParams, Solver};
use clothlab_cpu::{CpuSolver, Exec};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

fn substep(c: &mut Criterion) {
    let mut group = c.benchmark_group("substep");
    group.sample_size(20);
    let sizes: Vec<u32> = std::env::var("CLOTHLAB_BENCH_SIZES")
        .ok()
        .map(|s| s.split(',').filter_map(|x| x.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![128, 256, 512, 1024]);
    let params = SimParams::default();
    for &n in &sizes {
        group.throughput(Throughput::Elements(n as u64 * n as u64));
        for (name, exec, fused) in [
            ("serial", Exec::Serial, true),
            ("rayon", Exec::Parallel, true),
            ("serial-kernels", Exec::Serial, false),
            ("rayon-kernels", Exec::Parallel, false),
        ] {
            let mut s = CpuSolver::new(exec, Scene::with_n(n), params.clone()).unwrap();
            s.time_kernels = false;
            s.fused = fused;
            // Let the cloth fall for a few frames so the measured step sees contacts and
            // stretched springs, not only the flat sheet.
            for _ in 0..8 {
                s.step_frame().unwrap();
            }
            // Whole frames (the fused sweep writes the state back once a frame), reported
            // per substep.
            group.bench_with_input(BenchmarkId::new(name, n), &n, |b, _| {
                b.iter_custom(|frames| {
                    let t = Instant::now();
                    for _ in 0..frames {
                        black_box(&mut s).step_frame().unwrap();
                    }
                    t.elapsed() / params.substeps
                });
            });
        }
    }
    group.finish();
}

fn config() -> Criterion {
    Criterion::default().warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(4))
}

criterion_group! { name = benches; config = config(); targets = substep }
criterion_main!(benches);
