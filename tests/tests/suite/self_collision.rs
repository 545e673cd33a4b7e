//! Self-collision on every backend: the heap scene keeps its layers apart, every GPU
//! kernel of it matches its twin on both APIs (the hash's scatter, which places with
//! atomics in any order, bucket by bucket as sets), and a rollout through the contacts
//! follows the CPU.

use std::path::Path;

use clothlab_core::crossings;
use clothlab_core::{Scene, SceneFile, SimParams, Solver};
use clothlab_cpu::self_collide::{bucket_range, hash_words, table_size};
use clothlab_cpu::validate::validate_rollout;
use clothlab_cpu::{CpuSolver, Exec};
use clothlab_engine::Variant;
use clothlab_engine::kernels::{
    HASH_COUNT, HASH_SCATTER, KernelRef, SELF_COLLIDE_MESH, SELF_COLLISION, STRAIN_LIMIT_COUNT,
    STRAIN_LIMIT_INLINE_COUNT, STRAIN_LIMIT_STRIP_COUNT,
};
use clothlab_engine::recipe::Command;
use clothlab_engine::validate::{KernelInput, KernelRunner, validate_kernels_with};
use clothlab_tests::{assert_checks, backend, or_skip};
use clothlab_vulkan::vulkan_solver;
use clothlab_wgpu::{SolverOptions, wgpu_solver};

fn heap(n: u32) -> (Scene, SimParams) {
    let f = SceneFile::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/heap.toml")).unwrap();
    assert!(f.params.self_collision.particles());
    let mut scene = f.scene;
    scene.cloth.n = n;
    (scene, f.params)
}

/// The smallest distance between two particles that may collide (not grid neighbours,
/// farther apart at rest than 2t), by brute force.
fn closest_candidates(pos: &[[f32; 4]], p: &clothlab_core::StepParams) -> f32 {
    let mut best = f32::INFINITY;
    for a in 0..pos.len() {
        for b in a + 1..pos.len() {
            if clothlab_cpu::self_collide::candidates(p, a as u32, b as u32) {
                let d = (0..3).map(|k| (pos[a][k] - pos[b][k]).powi(2)).sum::<f32>().sqrt();
                best = best.min(d);
            }
        }
    }
    best
}

clothlab_tests::per_backend!(the_heap_keeps_its_layers_apart);

fn the_heap_keeps_its_layers_apart(name: &str) {
    // n = 32, 60 frames (1 s: the cloth lands at 0.25 s and folds over).
    // Every pair that may collide ends at least half the thickness apart (the
    // bound; the response aims at the whole thickness, and a substep's motion and several
    // contacts at once leave less). Without self-collision the layers pass through each
    // other: the same check fails, so it can (the next test).
    let (scene, params) = heap(32);
    let t = params.self_thickness;
    let sp = clothlab_core::StepParams::new(&params, &scene, None);
    let triangles = clothlab_core::build(&scene, &params).unwrap().1.triangles;
    let Some(mut s) = backend(name, &scene, &params) else { return };
    for _ in 0..HEAP_FRAMES {
        s.step_frame().unwrap();
    }
    let pos = s.state().unwrap().pos;
    // Particles kept apart are not surfaces kept apart: at n = 32 the thickness is 0.62
    // of the spacing, under the 0.71 a particle needs not to slip between four others,
    // and edges pass through triangles (core::crossings; measured 5 on the CPU and
    // wgpu, 254 on naive Vulkan, 589 without self-collision). Printed, not bounded:
    // the contact between triangles is what bounds them.
    let crossed = crossings::count(&pos, &triangles).pairs;
    let closest = closest_candidates(&pos, &sp);
    let lowest = pos.iter().map(|p| p[1]).fold(f32::INFINITY, f32::min);
    println!(
        "{name:16} closest pair that may collide {closest:.4} m (thickness {t} m); lowest {lowest:.4} m; {crossed} crossings"
    );
    assert!(closest >= 0.5 * t, "{name}: two layers {closest} m apart, under half the thickness {t}");
    // Landed: the lowest particle rests at the floor's 1 cm margin (measured 0.0099 to
    // 0.0100 m); 5 cm is far below the 0.25 m its lower edge starts at.
    assert!(lowest < 0.05, "{name}: the cloth has not landed (lowest point {lowest} m)");
}

/// Frames the heap of n = 32 falls in the layer tests (1 s).
const HEAP_FRAMES: u32 = 60;

#[test]
fn without_self_collision_the_heaps_layers_meet_and_cross() {
    // What makes the layer test able to fail: the same heap, the same frames, with
    // self-collision off.
    let (scene, params) = heap(32);
    let t = params.self_thickness;
    let sp = clothlab_core::StepParams::new(&params, &scene, None);
    let triangles = clothlab_core::build(&scene, &params).unwrap().1.triangles;
    let off = SimParams { self_collision: clothlab_core::SelfCollision::Off, ..params };
    let mut s = CpuSolver::new(Exec::Parallel, scene, off).unwrap();
    for _ in 0..HEAP_FRAMES {
        s.step_frame().unwrap();
    }
    let pos = s.state().unwrap().pos;
    let closest = closest_candidates(&pos, &sp);
    let crossed = crossings::count(&pos, &triangles).pairs;
    println!("without self-collision  closest pair {closest:.4} m, {crossed} crossings");
    assert!(closest < 0.5 * t, "without self-collision the layers should meet ({closest} m)");
    // And pass through each other: the counter sees it.
    assert!(crossed > 0, "without self-collision the layers should cross");
}

#[test]
fn the_heap_as_shipped_never_passes_through_itself_on_the_cpu() {
    // The scene file's n = 48: the thickness (0.02 m) is 0.94 of the spacing, over the
    // 0.71 the particle contact needs (docs/scenes.md). Every 5th frame of 150 (2.5 s:
    // landed and folded) has no edge through a triangle.
    let (scene, params) = heap(48);
    let triangles = clothlab_core::build(&scene, &params).unwrap().1.triangles;
    let mut s = CpuSolver::new(Exec::Parallel, scene, params).unwrap();
    for f in 1..=150 {
        s.step_frame().unwrap();
        if f % 5 == 0 {
            let c = crossings::count(&s.state_ref().pos, &triangles);
            assert_eq!(c.pairs, 0, "frame {f}: {} edges of {} through a triangle", c.pairs, c.edges);
        }
    }
}

/// Every self-collision kernel of `runner`'s recipe (`recipe`) against its twin, and the
/// scatter (atomics, in any order) against the twins' hash: the buckets' words (their
/// starts) bit for bit, each bucket's slots (positions and slot words) as a set.
fn check_kernels(
    label: &str,
    runner: &mut dyn KernelRunner,
    recipe: Vec<KernelRef>,
    scene: &Scene,
    params: &SimParams,
) {
    let mut kernels: Vec<_> = recipe
        .into_iter()
        .filter(|k| {
            SELF_COLLISION.contains(&k.def)
                || [&STRAIN_LIMIT_COUNT, &STRAIN_LIMIT_INLINE_COUNT, &STRAIN_LIMIT_STRIP_COUNT, &SELF_COLLIDE_MESH]
                    .contains(&k.def)
        })
        .collect();
    // The heap strain-limits: the hash's count runs in the last strain pass (after its
    // counts, or counting for itself, inline or down strips, as the optimized preset's
    // does), not alone.
    let fused = *kernels
        .iter()
        .find(|k| [&STRAIN_LIMIT_COUNT, &STRAIN_LIMIT_INLINE_COUNT, &STRAIN_LIMIT_STRIP_COUNT].contains(&k.def))
        .unwrap_or_else(|| panic!("{label}: {kernels:?}"));
    assert!(!kernels.iter().any(|k| k.def == &HASH_COUNT), "{label}: {kernels:?}");
    assert_eq!(kernels.len(), SELF_COLLISION.len(), "{label}: {kernels:?}");
    // The count alone too (what a recipe without a strain pass runs).
    kernels.push(HASH_COUNT.flavor(fused.flavor));
    let checks = validate_kernels_with(runner, &kernels, scene, 9, params).unwrap();
    // Five checked by the loop (the scatter by the test below), every buffer of each.
    assert_eq!(checks.len(), 5 * clothlab_engine::validate::COMPARED_BUFFERS, "{label}");
    assert_checks(label, &checks);
    let input = KernelInput::for_scene(scene, 9, params).unwrap();
    let bits = |v: &Vec<[f32; 4]>| v.iter().map(|e| e.map(f32::to_bits)).collect::<Vec<_>>();
    let scatter = kernels.iter().find(|k| k.def == &HASH_SCATTER).unwrap();
    let commands = [Command::Dispatch(*scatter)];
    let mut want = input.for_kernel(*scatter);
    let mut got = want.clone();
    input.engine.run(&commands, &input.p, 0, &mut want);
    runner.run_commands(&commands, &input.p, &mut got).unwrap();
    let np = want.pos.len();
    let size = table_size(np);
    let (cw, cg) = (hash_words(&want.aux[2]), hash_words(&got.aux[2]));
    assert!(cw == cg, "{label}: the buckets' starts after the scatter");
    assert!(bits(&want.aux[3]) == bits(&got.aux[3]), "{label}: aux3 after the scatter");
    let (pw, pg) = (bits(&want.aux[4]), bits(&got.aux[4]));
    let mut slots = 0;
    for b in 0..size {
        let (start, end) = bucket_range(cw, b, size, np as u32);
        let set = |v: &[[u32; 4]]| {
            let mut s = v[start as usize..end as usize].to_vec();
            s.sort_unstable();
            s
        };
        assert_eq!(set(&pw), set(&pg), "{label}: bucket {b}'s particles (positions and slot words)");
        slots += end - start;
    }
    assert_eq!(slots as usize, np, "{label}: every slot in one bucket");
}

#[test]
fn every_self_collision_kernel_matches_its_twin_and_a_rollout_through_the_contacts_follows_the_cpu() {
    // n = 33 (not a multiple of the workgroup; 1089 particles, 4096 buckets). The rollout
    // of the optimized variant runs 40 frames (640 substeps): the cloth lands at frame 14
    // and folds onto itself. The naive variant adds spring forces with float atomics in
    // any order: a folding cloth amplifies those last-bit differences into other folds
    // (measured: 0.13 m apart after 640 substeps, every kernel within its bound), so its
    // rollout stops before the landing (12 frames), and its self-collision kernels are
    // checked one by one above.
    let (scene, params) = heap(33);
    for (v, frames) in [(Variant::NAIVE, 12), (Variant::OPTIMIZED, 40)] {
        let wgpu = || or_skip(wgpu_solver(v, scene.clone(), params.clone(), SolverOptions::default()), "wgpu");
        if let (Some(mut w), Some(mut fresh)) = (wgpu(), wgpu()) {
            let label = format!("wgpu {}", v.label());
            let recipe = w.recipe_kernels();
            check_kernels(&label, &mut w, recipe, &scene, &params);
            assert_checks(&label, &[validate_rollout(&mut fresh, frames).unwrap()]);
        }
        let vulkan = || or_skip(vulkan_solver(v, scene.clone(), params.clone(), true, SolverOptions::default()), "vk");
        if let (Some(mut k), Some(mut fresh)) = (vulkan(), vulkan()) {
            let label = format!("vk {}", v.label());
            let recipe = k.recipe_kernels();
            check_kernels(&label, &mut k, recipe, &scene, &params);
            assert_checks(&label, &[validate_rollout(&mut fresh, frames).unwrap()]);
            for s in [&k, &fresh] {
                let m = s.engine().take_validation_messages();
                assert!(m.is_empty(), "validation layer: {m:#?}");
            }
        }
    }
}

/// The smallest distance between two particles of a mesh that may collide (sharing no
/// spring), by brute force.
fn closest_mesh_candidates(pos: &[[f32; 4]], table: &clothlab_core::grid::Rows<clothlab_core::SpringSlot>) -> f32 {
    let mut best = f32::INFINITY;
    for a in 0..pos.len() {
        for b in a + 1..pos.len() {
            if clothlab_cpu::self_collide::mesh_candidates(table, a, b) {
                let d = (0..3).map(|k| (pos[a][k] - pos[b][k]).powi(2)).sum::<f32>().sqrt();
                best = best.min(d);
            }
        }
    }
    best
}

clothlab_tests::per_backend!(a_mesh_heap_keeps_its_layers_apart);

/// The round tablecloth's heap (`scenes/mesh-heap.toml`), its tables, and the frames it
/// falls (50, 0.83 s: it lands at 0.24 s and its top reaches the floor by 0.5 s).
fn mesh_heap() -> (Scene, SimParams, clothlab_core::ClothTopology, u32) {
    let f = SceneFile::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/mesh-heap.toml")).unwrap();
    let (_, topo) = clothlab_core::build(&f.scene, &f.params).unwrap();
    (f.scene, f.params, topo, 50)
}

fn a_mesh_heap_keeps_its_layers_apart(name: &str) {
    // The round tablecloth (2813 particles) dropped edge first onto the floor: it lands
    // and folds over; the run without self-collision (the next test) shows that the layers
    // have met by then (the check can fail at this length). As for the grid's heap: every
    // pair that may collide (no spring between them) ends at least half the thickness
    // apart on every backend (measured 0.0107–0.0115 m for t = 0.012 m); without
    // self-collision the same check fails (0.0007 m).
    let (scene, params, topo, frames) = mesh_heap();
    let t = params.self_thickness;
    let Some(mut s) = backend(name, &scene, &params) else { return };
    for _ in 0..frames {
        s.step_frame().unwrap();
    }
    let pos = s.state().unwrap().pos;
    let closest = closest_mesh_candidates(&pos, &topo.slots);
    let lowest = pos.iter().map(|p| p[1]).fold(f32::INFINITY, f32::min);
    println!("{name:16} closest pair that may collide {closest:.4} m (thickness {t} m); lowest {lowest:.4} m");
    assert!(closest >= 0.5 * t, "{name}: two layers {closest} m apart, under half the thickness {t}");
    assert!(lowest < 0.05, "{name}: the cloth has not landed (lowest point {lowest} m)");
}

#[test]
fn without_self_collision_a_mesh_heaps_layers_meet_and_its_kernels_match_their_twins() {
    // The mesh heap's check can fail (its layers meet without self-collision); then the
    // self-collision kernels of the mesh (the response its own: neighbours from the table)
    // against their twins, the scatter as sets.
    let (scene, params, topo, frames) = mesh_heap();
    let t = params.self_thickness;
    let off = SimParams { self_collision: clothlab_core::SelfCollision::Off, ..params.clone() };
    let mut s = CpuSolver::new(Exec::Parallel, scene.clone(), off).unwrap();
    for _ in 0..frames {
        s.step_frame().unwrap();
    }
    let closest = closest_mesh_candidates(&s.state().unwrap().pos, &topo.slots);
    println!("without self-collision: closest pair {closest:.4} m");
    assert!(
        closest < 0.5 * t,
        "without self-collision the layers stayed apart too ({closest} m): the test cannot fail"
    );
    let vulkan =
        or_skip(vulkan_solver(Variant::OPTIMIZED, scene.clone(), params.clone(), true, SolverOptions::default()), "vk");
    if let Some(mut k) = vulkan {
        let recipe = k.recipe_kernels();
        assert!(recipe.iter().any(|r| r.def == &SELF_COLLIDE_MESH), "{recipe:?}");
        check_kernels("vk mesh", &mut k, recipe, &scene, &params);
        let m = k.engine().take_validation_messages();
        assert!(m.is_empty(), "validation layer: {m:#?}");
    }
    if let Some(mut g) =
        or_skip(wgpu_solver(Variant::NAIVE, scene.clone(), params.clone(), SolverOptions::default()), "wgpu")
    {
        let recipe = g.recipe_kernels();
        check_kernels("wgpu naive mesh", &mut g, recipe, &scene, &params);
    }
}
