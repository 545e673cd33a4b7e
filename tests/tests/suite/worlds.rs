//! A batch of worlds on each GPU API (`GpuSolver::new_worlds`, engine/src/worlds.rs):
//! every kernel dispatched once for all worlds, and world k computing, bit for bit, what a
//! single run of the scene with world k's parameters computes on the same API and recipe
//! (whose bits are the CPU's: scenes.rs, integrators.rs), under Verlet, XPBD, RK4,
//! implicit Euler and VBD, on a grid and a mesh. What a batch cannot share yet is refused in one line.

use clothlab_core::scene::ClothSpec;
use clothlab_core::{Integrator, Scene, SimParams, Solver};
use clothlab_engine::{Batch, VariantSpec};
use clothlab_tests::Api;

/// The default scene (floor, three spheres, top corners pinned) at 18 × 18: rows that
/// are not a whole number of the gathers' blocks of four.
fn scene() -> Scene {
    Scene { cloth: ClothSpec { n: 18, ..ClothSpec::default() }, ..Scene::default() }
}

/// The default scene at 12 × 12.
fn small() -> Scene {
    Scene { cloth: ClothSpec { n: 12, ..ClothSpec::default() }, ..Scene::default() }
}

/// World k's parameters: damping, wind, gravity and drag differ from world to world.
fn world(k: usize) -> SimParams {
    let k = k as f32;
    SimParams {
        damping: 0.0005 + 0.002 * k,
        wind: [1.5 * k, 0.0, -0.5 * k],
        gravity: [0.0, -9.81 + 0.7 * k, 0.0],
        air_drag: 0.1 + 0.05 * k,
        // Tight enough that the strain passes move particles in every world.
        strain_limit: 0.001 / (1.0 + k),
        ..SimParams::default()
    }
}

/// The recipes: the optimized one (the gathers fused, the wind in the forces, the normals
/// once a frame, the strain limit counting for itself) and the kernels one by one (forces,
/// springs, integrate, collide, strain count and pass, both normals kernels).
fn specs() -> [VariantSpec; 2] {
    [
        VariantSpec::parse("optimized", &[]).expect("a preset"),
        VariantSpec::parse("naive", &["springs=gather".into(), "normals=gather".into()]).expect("switches"),
    ]
}

fn bits(v: &[[f32; 4]]) -> Vec<u32> {
    v.iter().flatten().map(|x| x.to_bits()).collect()
}

/// Every world's state against its single run's, bit for bit.
fn assert_worlds_are_their_runs(batch: &mut dyn Batch, singles: &mut [Box<dyn Solver>], what: &str) {
    assert_worlds_within(batch, singles, what, 0.0)
}

/// Every world's state against its single run's: bit for bit where `tol` is 0, else
/// within `tol` (m, m/s) word by word.
fn assert_worlds_within(batch: &mut dyn Batch, singles: &mut [Box<dyn Solver>], what: &str, tol: f32) {
    for (k, single) in singles.iter_mut().enumerate() {
        let (got, want) = (batch.world_state(k).unwrap(), single.state().unwrap());
        assert!(got.pos.iter().flatten().all(|x| x.is_finite()), "{what}, world {k}: not finite");
        for (name, g, w) in [("positions", &got.pos, &want.pos), ("velocities", &got.vel, &want.vel)] {
            let (g, w) = (g.iter().flatten(), w.iter().flatten());
            let differ = g
                .zip(w)
                .filter(|(a, b)| if tol == 0.0 { a.to_bits() != b.to_bits() } else { (**a - **b).abs() > tol })
                .count();
            assert_eq!(
                differ, 0,
                "{what}, world {k}: {differ} words of its {name} differ from its single run's (by more than {tol})"
            );
        }
    }
}

/// The fan mesh (513 vertices, 960 triangles; scenes/mesh-fan.toml): the tables' paths,
/// each particle's own mass, the faces from the triangle list.
fn fan() -> Scene {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    clothlab_core::SceneFile::load(&dir.join("mesh-fan.toml")).unwrap_or_else(|e| panic!("{e}")).scene
}

fn a_gpu_batch_s_world_k_is_its_single_run_bit_for_bit(api: Api) {
    let [optimized, one_by_one] = specs();
    let (verlet, xpbd) = (Integrator::Verlet, Integrator::Xpbd);
    let rows = [
        (scene(), optimized.clone(), verlet),
        (scene(), one_by_one, verlet),
        (scene(), optimized.clone(), xpbd),
        (scene(), optimized.clone(), Integrator::Rk4),
        (scene(), optimized.clone(), Integrator::Implicit),
        (scene(), optimized.clone(), Integrator::Vbd),
        (fan(), optimized.clone(), verlet),
        (fan(), optimized.clone(), xpbd),
        (fan(), optimized, Integrator::Vbd),
        // The naive recipe as it is: the springs and the normals scattered with atomics.
        (scene(), VariantSpec::parse("naive", &[]).expect("a preset"), verlet),
    ];
    for (sc, spec, integrator) in rows {
        // Float atomics sum in the adapter's order, which a GPU may vary from run to run
        // (lavapipe on one thread does not: 0 there); a scatter that read another world's
        // particles would be off by centimetres.
        let tol = if spec.base.springs == clothlab_engine::variant::Accumulate::Scatter { 1e-5 } else { 0.0 };
        // Two XPBD iterations: λ carried from the first to the second, read where it was left.
        let worlds: Vec<SimParams> = (0..4).map(|k| SimParams { integrator, xpbd_iterations: 2, ..world(k) }).collect();
        let cloth = if sc.cloth.is_mesh() { "fan" } else { "grid" };
        let what = format!("{api} {cloth} {} {spec:?}", integrator.name());
        let Some(batch) = api.batch(spec.clone(), &sc, worlds.clone()) else { return };
        let mut batch = batch.unwrap_or_else(|e| panic!("{what}: {e}"));
        let mut singles: Vec<Box<dyn Solver>> =
            worlds.iter().map(|p| api.solver(spec.clone(), &sc, p).expect("an adapter").into_solver()).collect();
        // Every kernel of the batch's recipe is a `_w` twin: one dispatch for all worlds.
        let kernels = batch.recipe_kernels();
        assert!(kernels.iter().all(|k| k.shader_name().ends_with("_w")), "{what}: {kernels:?}");
        for _ in 0..2 {
            batch.step_frame().unwrap();
            singles.iter_mut().for_each(|s| s.step_frame().unwrap());
        }
        assert_worlds_within(batch.as_mut(), &mut singles, &what, tol);
        // The worlds differ (so a world computed with another's parameters would show).
        let (w0, w3) = (batch.world_state(0).unwrap(), batch.world_state(3).unwrap());
        assert_ne!(bits(&w0.pos), bits(&w3.pos), "{what}: worlds 0 and 3 moved alike");
        // New parameters, world by world (world k gets world 3 − k's), reach their worlds.
        let changed: Vec<SimParams> = worlds.iter().rev().cloned().collect();
        batch.set_world_params(changed.clone()).unwrap();
        for (s, p) in singles.iter_mut().zip(&changed) {
            s.set_params(p.clone()).unwrap();
        }
        batch.step_frame().unwrap();
        singles.iter_mut().for_each(|s| s.step_frame().unwrap());
        assert_worlds_within(batch.as_mut(), &mut singles, &format!("{what}, parameters changed"), tol);
        // A world's state set from outside is what it then holds, the others unchanged.
        let before = batch.world_state(1).unwrap();
        let mut moved = batch.world_state(2).unwrap();
        moved.pos.iter_mut().for_each(|x| x[1] += 0.25);
        batch.set_world_state(2, &moved).unwrap();
        assert_eq!(bits(&batch.world_state(2).unwrap().pos), bits(&moved.pos), "{what}: world 2 set");
        assert_eq!(bits(&batch.world_state(1).unwrap().pos), bits(&before.pos), "{what}: world 1 untouched");
        batch.api_check().unwrap();
    }
}
clothlab_tests::per_api!(a_gpu_batch_s_world_k_is_its_single_run_bit_for_bit);

/// Contact in a batch: each world's self-collision hash is its own (its table, its
/// blocks, its slots), and so are its contact between triangles' integers, pairs, starts
/// and bounds; so the worlds — copies in the same place, every particle beside its copies
/// in the other worlds — push nothing across: world k is its single run bit for bit.
/// Between particles: the hash counted by hash_count (one by one) or by the strain limit's
/// last pass (optimized), with and without Coulomb friction, on a grid and a mesh;
/// between triangles with friction on the grid (its triangles and edges), under Verlet
/// and under VBD (its terms in the colour sweep; the other integrators run the contact's
/// kernels as Verlet does).
fn a_gpu_batch_s_contact_keeps_to_each_world(api: Api) {
    use clothlab_core::SelfCollision::{Particles, Triangles};
    let [optimized, one_by_one] = specs();
    let verlet = Integrator::Verlet;
    let rows = [
        (scene(), optimized.clone(), 0.0, Particles, verlet),
        (scene(), one_by_one, 0.8, Particles, verlet),
        (fan(), optimized.clone(), 0.8, Particles, verlet),
        // The contact between triangles on a 12 × 12 grid: its kernels cost lavapipe
        // ~5 ms a world-substep at 18 × 18.
        (small(), optimized.clone(), 0.5, Triangles, verlet),
        (small(), optimized, 0.5, Triangles, Integrator::Vbd),
    ];
    for (sc, spec, mu, mode, integrator) in rows {
        let t = if sc.cloth.is_mesh() || mode == Triangles { 0.004 } else { 0.02 };
        // The contact between triangles costs lavapipe ~5 ms a world-substep: two worlds
        // and a frame of it (its worlds still in the same place, moved apart by gravity).
        let (envs, frames) = if mode == Triangles { (2, 1) } else { (4, 2) };
        let worlds: Vec<SimParams> = (0..envs)
            .map(|k| SimParams {
                integrator,
                self_collision: mode,
                self_thickness: t,
                static_friction: mu,
                kinetic_friction: 0.5 * mu,
                ..world(k)
            })
            .collect();
        let cloth = if sc.cloth.is_mesh() { "fan" } else { "grid" };
        let what = format!("{api} {cloth} {mode:?} {} μs {mu} {spec:?}", integrator.name());
        let Some(batch) = api.batch(spec.clone(), &sc, worlds.clone()) else { return };
        let mut batch = batch.unwrap_or_else(|e| panic!("{what}: {e}"));
        let kernels = batch.recipe_kernels();
        assert!(kernels.iter().all(|k| k.shader_name().ends_with("_w")), "{what}: {kernels:?}");
        let response = match (mode, integrator) {
            (Particles, _) => "self_collide",
            (_, Integrator::Vbd) => "vbd_colour_tri",
            _ => "tri_impulse_share",
        };
        assert!(kernels.iter().any(|k| k.shader_name().starts_with(response)), "{what}: {kernels:?}");
        let mut singles: Vec<Box<dyn Solver>> =
            worlds.iter().map(|p| api.solver(spec.clone(), &sc, p).expect("an adapter").into_solver()).collect();
        let np = sc.num_particles();
        let apart = if mode == Triangles && !sc.cloth.is_mesh() { 3 * sc.cloth.n as usize } else { np / 2 };
        let every = if mode == Triangles { 31 } else { 7 };
        // Each world crowded its own way (one more particle over), in the same place: a
        // world that read another's pairs or counts would take the wrong ones.
        let built = singles[0].state().unwrap();
        let starts: Vec<_> = (0..envs)
            .map(|k| {
                let mut s = built.clone();
                clothlab_engine::kernels::crowd(&mut s.pos, t, apart + k, every);
                s
            })
            .collect();
        for (k, s) in singles.iter_mut().enumerate() {
            s.set_state(&starts[k]).unwrap();
            batch.set_world_state(k, &starts[k]).unwrap();
        }
        let start = &starts[0];
        // World 0 without the contact, from the same start: the contacts move it.
        let apart = SimParams { self_collision: clothlab_core::SelfCollision::Off, ..worlds[0].clone() };
        let mut without = api.solver(spec.clone(), &sc, &apart).expect("an adapter").into_solver();
        without.set_state(start).unwrap();
        for _ in 0..frames {
            batch.step_frame().unwrap();
            singles.iter_mut().for_each(|s| s.step_frame().unwrap());
            without.step_frame().unwrap();
        }
        assert_worlds_are_their_runs(batch.as_mut(), &mut singles, &what);
        let differ = bits(&batch.world_state(0).unwrap().pos)
            .iter()
            .zip(bits(&without.state().unwrap().pos))
            .filter(|(a, b)| **a != *b)
            .count();
        assert!(differ > 0, "{what}: the contact changed nothing (no contacts to keep apart)");
        batch.api_check().unwrap();
    }
}
clothlab_tests::per_api!(a_gpu_batch_s_contact_keeps_to_each_world);

#[test]
fn what_a_gpu_batch_cannot_share_is_refused_in_one_line_naming_the_world_or_the_kernel() {
    let (sc, spec) = (scene(), VariantSpec::parse("optimized", &[]).unwrap());
    let refused = |worlds: Vec<SimParams>| match Api::Wgpu.batch(spec.clone(), &sc, worlds) {
        None => None,
        Some(Ok(_)) => panic!("a batch it cannot run was built"),
        Some(Err(e)) => Some(e.to_string()),
    };
    let softer = SimParams { structural_stiffness: 0.5 * world(1).structural_stiffness, ..world(1) };
    let Some(e) = refused(vec![world(0), softer]) else { return };
    assert!(e.contains("world 1") && e.contains("stiffness") && !e.contains('\n'), "{e}");
    // The tiled substep (`fusion=tile`) has no world dimension yet.
    let tiled = VariantSpec::parse("optimized", &["fusion=tile".into()]).unwrap();
    let e = match Api::Wgpu.batch(tiled, &sc, vec![world(0), world(1)]) {
        Some(Err(e)) => e.to_string(),
        other => panic!("a tiled batch: {:?}", other.map(|r| r.is_ok())),
    };
    assert!(e.contains("kernel substep_tile") && e.contains("no world dimension"), "{e}");
    // A world's bad value is refused naming it, nothing changed.
    let mut batch = Api::Wgpu.batch(spec, &sc, (0..3).map(world).collect()).unwrap().unwrap();
    let bad = vec![world(0), world(1), SimParams { damping: -1.0, ..world(2) }];
    let e = batch.set_world_params(bad).unwrap_err().to_string();
    assert!(e.starts_with("world 2:"), "{e}");
    assert_eq!(batch.world_params()[2], world(2), "world 2's parameters kept");
    let e = batch.world_state(3).unwrap_err().to_string();
    assert!(e.contains("world 3") && e.contains("3 worlds"), "{e}");
    // A cloth of 9 particles: its hash table is smaller than one of the scan's blocks.
    let tiny = Scene { cloth: ClothSpec { n: 3, ..ClothSpec::default() }, ..Scene::default() };
    let touching = SimParams { self_collision: clothlab_core::SelfCollision::Particles, ..world(0) };
    let e = match Api::Wgpu.batch(VariantSpec::parse("optimized", &[]).unwrap(), &tiny, vec![touching; 2]) {
        Some(Err(e)) => e.to_string(),
        other => panic!("a batch of 9-particle worlds with self-collision: {:?}", other.map(|r| r.is_ok())),
    };
    assert!(e.contains("16 particles") && e.contains("has 9") && !e.contains('\n'), "{e}");
}
