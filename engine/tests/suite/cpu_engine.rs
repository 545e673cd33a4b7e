//! The CPU engine against the fast CPU solvers, and the bisection's logic on a runner that
//! is wrong on purpose.

use clothlab_core::step_params::StepParams;
use clothlab_core::timing;
use clothlab_core::{Scene, SimParams, Solver, SolverError};
use clothlab_cpu::validate::ROLLOUT_BOUND_PER_SUBSTEP;
use clothlab_cpu::{CpuSolver, Exec};
use clothlab_engine::kernels::{self as k, HostBuffers, KernelRef};
use clothlab_engine::recipe::{Command, recipe};
use clothlab_engine::validate::{KernelRunner, bisect, validate_kernels};
use clothlab_engine::{CpuEngine, RecipeSolver, Variant};

fn bits(v: &[[f32; 4]]) -> Vec<[u32; 4]> {
    v.iter().map(|p| p.map(f32::to_bits)).collect()
}

#[test]
fn the_rows_solvers_compute_the_bits_of_the_cpu_engine_running_the_optimized_recipe() {
    // 37: rows that are not a multiple of the 8 SIMD lanes; 64: whole lanes. Wind on and
    // two strain passes, so every kernel matters. Bit for bit: the rows solvers are the
    // same arithmetic fused and on lanes, so any difference is a bug, not rounding. The
    // recipe with normals once per frame (the wind computed in the forces gather) too: the
    // same arithmetic in another order of kernels, so the same bits after every frame.
    let params = SimParams { wind: [2.0, 0.0, 1.0], strain_iterations: 2, ..SimParams::default() };
    let frame_normals = Variant::OPTIMIZED;
    let mut substep_normals = Variant::OPTIMIZED;
    substep_normals.set("normals", "gather").unwrap();
    for (n, variant) in [(37, substep_normals), (64, substep_normals), (37, frame_normals)] {
        let scene = Scene::with_n(n);
        let mut engine = RecipeSolver::new(Exec::Serial, variant, scene.clone(), params.clone()).unwrap();
        assert_eq!(engine.frame_end().is_empty(), variant == substep_normals);
        let mut serial = CpuSolver::new(Exec::Serial, scene.clone(), params.clone()).unwrap();
        let mut rayon = CpuSolver::new(Exec::Parallel, scene, params.clone()).unwrap();
        for frame in 0..6 {
            engine.step_frame().unwrap();
            serial.step_frame().unwrap();
            rayon.step_frame().unwrap();
            let e = engine.state().unwrap();
            for s in [&serial, &rayon] {
                let st = s.state_ref();
                for (name, a, b) in [
                    ("pos", &e.pos, &st.pos),
                    ("vel", &e.vel, &st.vel),
                    ("force", &e.force, &st.force),
                    ("normal", &e.normal, &st.normal),
                ] {
                    assert!(
                        bits(a) == bits(b),
                        "n = {n}, frame {frame}: {} {name} differs from the CPU engine running {variant}",
                        s.name()
                    );
                }
            }
        }
    }
}

#[test]
fn the_naive_recipe_on_the_cpu_engine_stays_within_the_rollout_bound_of_the_optimized() {
    // The scatter adds each particle's springs in spring-list order, the gather in slot
    // order: rounding differs, within the rollout bound (1e-6 m per substep).
    let scene = Scene::with_n(32);
    let params = SimParams::default();
    let mut naive = RecipeSolver::new(Exec::Serial, Variant::NAIVE, scene.clone(), params.clone()).unwrap();
    let mut opt = RecipeSolver::new(Exec::Serial, Variant::OPTIMIZED, scene, params.clone()).unwrap();
    let frames = 8;
    for _ in 0..frames {
        naive.step_frame().unwrap();
        opt.step_frame().unwrap();
    }
    let (a, b) = (naive.state().unwrap(), opt.state().unwrap());
    let worst =
        a.pos.iter().zip(&b.pos).flat_map(|(p, q)| (0..3).map(move |c| (p[c] - q[c]).abs())).fold(0.0, f32::max);
    let bound = ROLLOUT_BOUND_PER_SUBSTEP * (frames * params.substeps) as f32;
    assert!(worst <= bound, "naive vs optimized on the CPU engine: {worst:e} m > {bound:e} m");
    assert!(naive.timings().get(timing::SPRINGS).is_some() && opt.timings().get(timing::FORCES_SPRINGS_WIND).is_some());
}

/// The CPU engine with one kernel wrong: after `bad` it adds `delta` to every free
/// particle's x.
struct Faulty {
    engine: CpuEngine,
    bad: &'static str,
    delta: f32,
}

impl KernelRunner for Faulty {
    fn kernels(&self) -> Vec<KernelRef> {
        self.engine.kernels()
    }
    fn run_commands(
        &mut self,
        commands: &[Command],
        p: &StepParams,
        bufs: &mut HostBuffers,
    ) -> Result<(), SolverError> {
        for c in commands {
            self.engine.command(c, p, 0, bufs);
            if matches!(c, Command::Dispatch(k) if k.def.name == self.bad) {
                bufs.pos.iter_mut().filter(|x| x[3] != 0.0).for_each(|x| x[0] += self.delta);
            }
        }
        Ok(())
    }
    fn adapter(&self) -> String {
        "faulty".into()
    }
}

#[test]
fn bisection_names_the_kernel_that_is_wrong_and_none_when_all_are_right() {
    let scene = Scene::with_n(16);
    let params = SimParams::default();
    let (_, topo) = clothlab_core::build(&scene, &params).unwrap();
    // The optimized step with the normals every substep, colliders in storage and loaded
    // neighbours: five dispatches (the strain pass counting for itself), one of them the
    // normals, whose fault must be found too.
    let mut v = Variant::OPTIMIZED;
    for (k, val) in [("normals", "gather"), ("colliders", "storage"), ("neighbours", "load")] {
        v.set(k, val).unwrap();
    }
    let commands = recipe(&v, 1, clothlab_engine::recipe::Integration::VERLET);
    let substeps = 32;
    for (bad, delta, want) in [
        ("integrate_collide", 1e-3, Some("integrate_collide_imm")),
        ("tri_normals", 1e-3, Some("tri_normals_imm")),
        // Below the bound of 32 substeps (3.2e-5 m) even as Verlet turns each offset into velocity
        // (Σ s · 1e-8 ≈ 5e-6 m).
        ("integrate_collide", 1e-8, None),
    ] {
        let mut runner = Faulty { engine: CpuEngine::new(Exec::Serial, scene.clone(), topo.clone()), bad, delta };
        let b = bisect(&mut runner, &commands, &scene, &params, substeps).unwrap();
        assert_eq!(b.splits.len(), 5, "one split per dispatch");
        assert_eq!(b.culprit.as_deref(), want, "{bad} off by {delta}: {:#?}", b.splits);
        // Only vertex_normals on the GPU, and the fault is in another kernel: exact.
        assert_eq!(b.splits[4].check.error, 0.0, "{bad}");
    }
}

#[test]
fn every_kernel_of_the_cpu_engine_passes_its_own_check() {
    // The checks' own sanity: the engine against itself is exact, poisoned outputs
    // included (a kernel that did not write its pure output would show NaN).
    let (_, topo) = clothlab_core::build(&Scene::with_n(20), &SimParams::default()).unwrap();
    let mut engine = CpuEngine::new(Exec::Parallel, Scene::with_n(20), topo);
    let kernels = engine.kernels();
    let checks = validate_kernels(&mut engine, &kernels, 20, 7).unwrap();
    assert!(!checks.is_empty());
    for c in &checks {
        assert!(c.max_abs == 0.0, "{} {}: {:e}", c.what, c.buffer, c.max_abs);
    }
    // Statistics kernels are checked by their own test, not here.
    assert!(checks.iter().all(|c| !c.what.starts_with("stats")));
    assert!(kernels.contains(&k::STATS.plain()));
}

/// A mesh on the CPU engine: every integrator's recipe (the GPU backends' commands, XPBD
/// by the mesh's passes) gives the CPU solvers' bits after every frame — the same
/// arithmetic in the same order, so any difference is a bug, not rounding.
#[test]
fn a_mesh_on_the_cpu_engine_computes_the_cpu_solvers_bits_with_every_integrator() {
    use clothlab_core::{Integrator, SceneFile};
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let file = SceneFile::load(&dir.join("mesh-skirt.toml")).unwrap_or_else(|e| panic!("{e}"));
    let mut substep_normals = Variant::OPTIMIZED;
    substep_normals.set("normals", "gather").unwrap();
    for integrator in Integrator::ALL {
        let params = SimParams { integrator, wind: [2.0, 0.0, 1.0], strain_iterations: 2, ..file.params.clone() };
        for variant in [Variant::OPTIMIZED, substep_normals] {
            let variant = variant.fit(&clothlab_engine::recipe::Caps {
                float_atomics: true,
                immediates: true,
                table_image: true,
                subgroups: true,
                grid: false,
                tile: true,
                sdf_image: true,
                cpu: true,
            });
            // Euler and RK2 refuse these springs (they need far softer ones): skipped.
            let mut engine = match RecipeSolver::new(Exec::Serial, variant, file.scene.clone(), params.clone()) {
                Err(SolverError::Param(e)) if matches!(integrator, Integrator::Euler | Integrator::Rk2) => {
                    assert!(e.to_string().contains("cannot integrate springs"), "{e}");
                    continue;
                }
                r => r.unwrap(),
            };
            let mut serial = CpuSolver::new(Exec::Serial, file.scene.clone(), params.clone()).unwrap();
            for frame in 0..3 {
                engine.step_frame().unwrap();
                serial.step_frame().unwrap();
                let (e, st) = (engine.state().unwrap(), serial.state_ref());
                for (name, a, b) in
                    [("pos", &e.pos, &st.pos), ("vel", &e.vel, &st.vel), ("normal", &e.normal, &st.normal)]
                {
                    let worst =
                        a.iter().zip(b).flat_map(|(p, q)| (0..3).map(move |c| (p[c] - q[c]).abs())).fold(0.0, f32::max);
                    assert!(
                        bits(a) == bits(b),
                        "{integrator:?} {variant}, frame {frame}: {name} differs by up to {worst:e}"
                    );
                }
            }
        }
    }
}
