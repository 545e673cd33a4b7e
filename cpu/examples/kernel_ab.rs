//! Times each CPU kernel's per-particle twin against the row fast path the solvers use, on
//! a draped cloth: `cargo run --release -p clothlab-cpu --example kernel_ab -- 256`.

use std::time::Instant;

use clothlab_core::{Scene, SimParams, Solver, StepParams};
use clothlab_cpu as cpu;
use clothlab_cpu::CpuSolver;
use clothlab_cpu::Exec;

fn median_us(mut f: impl FnMut(), reps: usize) -> f64 {
    let mut t: Vec<f64> = (0..reps)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64() * 1e6
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[reps / 2]
}

fn main() {
    let n: u32 = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(256);
    let params = SimParams::default();
    let scene = Scene::with_n(n);
    let mut s = CpuSolver::new(Exec::Serial, scene.clone(), params.clone()).unwrap();
    for _ in 0..30 {
        s.step_frame().unwrap();
    }
    let st = s.state().unwrap();
    let topo = s.topology().clone();
    let uni = topo.uniform_interior_slots();
    let p = StepParams::new(&params, &scene, None);
    let mut lanes = cpu::Lanes::default();
    lanes.fill(Exec::Serial, n as usize, &st.pos, Some(&st.vel));
    let mut lanes_p = cpu::Lanes::default();
    lanes_p.fill(Exec::Serial, n as usize, &st.pos, None);
    let mut l = cpu::Lanes::default();
    let fill = median_us(|| l.fill(Exec::Serial, n as usize, &st.pos, Some(&st.vel)), 50);
    println!("Serial lanes fill (pos+vel) {:7.1} ns/particle", fill * 1e3 / (n * n) as f64);
    let np = (n * n) as f64;
    let reps = 50;
    for exec in [Exec::Serial, Exec::Parallel] {
        let mut f = st.force.clone();
        let a = median_us(|| cpu::springs(exec, &topo.slots, &st.pos, &st.vel, &mut f), reps);
        let b = median_us(
            || cpu::springs_rows(exec, n as usize, &topo.slots, uni.as_ref(), None, &lanes, &st.pos, &st.vel, &mut f),
            reps,
        );
        println!("{exec:?} springs       twin {:7.1} ns/particle   rows {:7.1}", a * 1e3 / np, b * 1e3 / np);
        let mut o = st.pos.clone();
        let mut counts = vec![0.0; st.pos.len()];
        cpu::strain_count(exec, &p, &topo.slots, &st.pos, &mut counts);
        let a = median_us(|| cpu::strain_limit(exec, &p, &topo.slots, &topo.tethers, &st.pos, &counts, &mut o), reps);
        let b = median_us(
            || {
                cpu::strain_limit_rows(
                    exec,
                    &p,
                    &topo.slots,
                    uni.as_ref(),
                    &topo.tethers,
                    &lanes_p,
                    &st.pos,
                    &counts,
                    &mut o,
                )
            },
            reps,
        );
        println!("{exec:?} strain_limit  twin {:7.1} ns/particle   rows {:7.1}", a * 1e3 / np, b * 1e3 / np);
    }
}
