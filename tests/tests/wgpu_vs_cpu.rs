//! The wgpu kernels and solvers against the CPU twins.

use clothlab_core::cpu::{self, Exec};
use clothlab_core::grid::{ClothState, Grab, StepParams, V4};
use clothlab_core::{CpuSolver, Scene, SimParams, Solver};
use clothlab_tests::{gpu_required, rel_error};
use clothlab_wgpu::{Variant, WgpuSolver};

/// A wgpu solver, or `None` (with the reason printed) where no adapter exists and the
/// environment does not require one.
fn gpu(variant: Variant, scene: &Scene, params: &SimParams) -> Option<WgpuSolver> {
    match WgpuSolver::new(variant, scene.clone(), params.clone()) {
        Ok(s) => Some(s),
        Err(e) if !gpu_required() && e.to_string().contains("no GPU adapter") => {
            eprintln!("skipped: {e}");
            None
        }
        Err(e) => panic!("wgpu solver: {e}"),
    }
}

/// A draped, then randomly disturbed state: positions moved by up to ±0.3 spacing and
/// velocities of up to ±0.2 spacing per substep, from a seeded generator.
fn disturbed_state(scene: &Scene, params: &SimParams, seed: u64) -> (ClothState, clothlab_core::ClothTopology) {
    let mut s = CpuSolver::new(Exec::Serial, scene.clone(), params.clone()).unwrap();
    for _ in 0..15 {
        s.step_frame().unwrap();
    }
    let mut st = s.state().unwrap();
    let spacing = scene.cloth.size / (scene.cloth.n - 1) as f32;
    let mut rng = seed;
    let mut rand = move || {
        rng = rng.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((rng >> 40) as f32 / (1u64 << 24) as f32) - 0.5
    };
    for (p, q) in st.pos.iter_mut().zip(st.prev.iter_mut()) {
        if p[3] == 0.0 {
            continue;
        }
        for k in 0..3 {
            p[k] += 0.6 * spacing * rand();
            q[k] = p[k] - 0.4 * spacing * rand();
        }
    }
    for f in st.force.iter_mut() {
        for c in f.iter_mut().take(3) {
            *c = 1e-3 * rand();
        }
    }
    (st, s.topology().clone())
}

/// Per-vertex sums of the adjacent face normals (what the naive scatter accumulates).
fn face_sums(topo: &clothlab_core::ClothTopology, faces: &[V4]) -> Vec<V4> {
    topo.face_slots
        .iter()
        .map(|slots| {
            let mut s = [0.0f32; 4];
            for &t in slots.iter().filter(|&&t| t >= 0) {
                for k in 0..3 {
                    s[k] += faces[t as usize][k];
                }
            }
            s
        })
        .collect()
}

/// Every kernel alone on one grid size: GPU output vs the CPU twin on the same input.
fn kernels_match_on(n: u32) {
    let scene = Scene::with_n(n);
    let params = SimParams { wind: [1.5, 0.3, -2.0], ..SimParams::default() };
    let Some(mut g) = gpu(Variant::Optimized, &scene, &params) else { return };
    let (st, topo) = disturbed_state(&scene, &params, 0x5eed + n as u64);
    let grab = Some(Grab { particle: n * n / 2 + 3, target: [0.1, 1.2, 0.3] });
    let p = StepParams::new(&params, &scene, grab);
    let mut faces = vec![[0.0f32; 4]; topo.triangles.len()];
    cpu::tri_normals(Exec::Serial, &topo.triangles, &st.pos, &mut faces);
    let e = Exec::Serial;

    // (kernel, bound) — the bounds, relative to the largest magnitude in the buffer:
    // * 1e-5 for per-element kernels: a handful of f32 operations, each within the few
    //   ulps Vulkan allows for division and square root (2.5–3 ulp), and FMA contraction.
    // * 2e-5 for the gathers of up to 12 springs and the tethers: more operations.
    // * 1e-5 for the atomic scatters: the summation order is arbitrary and each spring
    //   force can be ~100× the net force it contributes to, so cancellation amplifies
    //   rounding. Measured on lavapipe: 0 for every gather (llvmpipe evaluates the same
    //   IEEE operations in the same order as the twins), 0.9e-7 – 1.4e-7 for the scatters.
    let mut cases: Vec<(&str, f32)> = vec![
        ("forces", 1e-5),
        ("springs", 2e-5),
        ("forces_springs", 2e-5),
        ("springs_scatter", 1e-5),
        ("integrate", 1e-5),
        ("collide", 1e-5),
        ("integrate_collide", 1e-5),
        ("strain_limit", 2e-5),
        ("tri_normals", 1e-5),
        ("tri_normals_scatter", 1e-5),
        ("vertex_normals", 2e-5),
        ("vertex_normals_naive", 2e-5),
    ];
    // Both atomic paths: compare-exchange loops always, float atomics where the adapter
    // has them (lavapipe does).
    if g.float_atomics() {
        cases.extend([("springs_scatter_f32", 1e-5), ("tri_normals_scatter_f32", 1e-5)]);
    } else {
        println!("float atomics not available on this adapter: only the compare-exchange path is tested");
    }
    for &(kernel, bound) in &cases {
        let mut input = st.clone();
        if kernel == "vertex_normals_naive" {
            input.normal = face_sums(&topo, &faces);
        }
        let (out, out_faces) = g.run_kernel(kernel, &input, &faces, grab).unwrap();
        let mut want = input.clone();
        let mut want_faces = faces.clone();
        let mut checks: Vec<(&str, Vec<V4>, Vec<V4>)> = Vec::new();
        match kernel {
            "forces" => cpu::forces(e, &p, &want.pos, &want.prev, &mut want.force),
            "springs" => cpu::springs(e, p.dt, &topo.slots, &want.pos, &want.prev, &mut want.force),
            "forces_springs" => {
                cpu::forces(e, &p, &want.pos, &want.prev, &mut want.force);
                cpu::springs(e, p.dt, &topo.slots, &want.pos, &want.prev, &mut want.force);
            }
            "springs_scatter" | "springs_scatter_f32" => {
                cpu::springs_scatter(p.dt, &topo.springs, &want.pos, &want.prev, &mut want.force)
            }
            "integrate" => cpu::integrate(e, &p, &want.force, &mut want.pos, &mut want.prev),
            "collide" => cpu::collide(e, &p, &scene.spheres, &scene.boxes, &mut want.pos, &mut want.prev),
            "integrate_collide" => {
                cpu::integrate(e, &p, &want.force, &mut want.pos, &mut want.prev);
                cpu::collide(e, &p, &scene.spheres, &scene.boxes, &mut want.pos, &mut want.prev);
            }
            "strain_limit" => {
                let mut o = want.pos.clone();
                cpu::strain_limit(e, &p, &topo.slots, &topo.tethers, &want.pos, &mut o);
                want.pos = o;
            }
            "tri_normals" => cpu::tri_normals(e, &topo.triangles, &want.pos, &mut want_faces),
            "tri_normals_scatter" | "tri_normals_scatter_f32" => {
                cpu::tri_normals(e, &topo.triangles, &want.pos, &mut want_faces);
                want.normal = face_sums(&topo, &want_faces);
            }
            "vertex_normals" => {
                cpu::vertex_normals(e, &p, &topo.face_slots, &faces, &mut want.normal, &mut want.force);
            }
            "vertex_normals_naive" => {
                cpu::vertex_normals(e, &p, &topo.face_slots, &faces, &mut want.normal, &mut want.force);
            }
            other => panic!("no CPU twin listed for {other}"),
        }
        checks.push(("pos", out.pos.clone(), want.pos.clone()));
        checks.push(("prev", out.prev.clone(), want.prev.clone()));
        checks.push(("force", out.force.clone(), want.force.clone()));
        checks.push(("normal", out.normal.clone(), want.normal.clone()));
        checks.push(("faces", out_faces.clone(), want_faces.clone()));
        for (what, got, want) in &checks {
            let err = rel_error(got, want);
            println!("n = {n:4}  {kernel:22} {what:7} rel. error {err:.2e}  (bound {bound:.0e})");
            assert!(
                err <= bound,
                "n = {n}, kernel {kernel}: {what} differs from the CPU twin by {err:e} (bound {bound:e})"
            );
        }
    }
}

#[test]
fn every_kernel_matches_its_cpu_twin_at_n_64() {
    kernels_match_on(64);
}

#[test]
fn every_kernel_matches_its_cpu_twin_at_sizes_that_are_not_multiples_of_64() {
    for n in [63, 65, 257] {
        kernels_match_on(n);
    }
}

#[test]
fn rollouts_of_200_substeps_stay_close_to_the_cpu() {
    let scene = Scene::with_n(64);
    let params = SimParams::default();
    let mut cpu_solver = CpuSolver::new(Exec::Serial, scene.clone(), params.clone()).unwrap();
    let Some(mut naive) = gpu(Variant::Naive, &scene, &params) else { return };
    let Some(mut opt) = gpu(Variant::Optimized, &scene, &params) else { return };
    let frames = 200u32.div_ceil(params.substeps); // 13 frames, 208 substeps
    let mut worst = [0.0f32; 2];
    for f in 1..=frames {
        cpu_solver.step_frame().unwrap();
        naive.step_frame().unwrap();
        opt.step_frame().unwrap();
        let want = cpu_solver.state().unwrap();
        let steps = (f * params.substeps) as f32;
        for (k, s) in [&mut naive, &mut opt].into_iter().enumerate() {
            let got = s.state().unwrap();
            let (d, _) = clothlab_tests::max_abs_diff(&got.pos, &want.pos);
            worst[k] = worst[k].max(d);
            // Differences start at a few ulps of a position (|x| ≈ 2 m: 2.4e-7 m) per
            // substep and Verlet carries them on as velocity, so they grow at most
            // linearly per step in a damped, strain-limited cloth: bound 1e-6 m per substep
            // (≈ 4 ulps), i.e. 0.2 mm after 208 substeps. Chaotic contacts could
            // amplify more. Measured on lavapipe: optimized 0 (bit-exact), naive 1.5e-5 m.
            let bound = 1e-6 * steps;
            assert!(d <= bound, "{}: positions differ by {d} m after {steps} substeps (bound {bound})", s.name());
        }
    }
    println!("max position difference over 208 substeps: naive {:.2e} m, optimized {:.2e} m", worst[0], worst[1]);
    // Naive against optimized, same bound derivation (both differ from the CPU).
    let (d, _) = clothlab_tests::max_abs_diff(&naive.state().unwrap().pos, &opt.state().unwrap().pos);
    assert!(d <= 2e-6 * (frames * params.substeps) as f32, "naive vs optimized: {d} m");
}
