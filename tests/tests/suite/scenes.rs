//! The scene files of `scenes/` on every backend: each loads and builds; the free-falling
//! cloth falls as y0 − ½ g t²; the tablecloth ends outside its box, every GPU backend
//! following the CPU, every kernel against its twin with the box in the scene.

use std::path::{Path, PathBuf};

use clothlab_core::{Scene, SceneFile, SimParams, Solver};
use clothlab_cpu::Exec;
use clothlab_cpu::validate::{compare, validate_rollout};
use clothlab_engine::Variant;
use clothlab_engine::validate::{KernelRunner, validate_kernels_with};
use clothlab_tests::{Api, assert_checks, backend, or_skip};
use clothlab_vulkan::vulkan_solver;
use clothlab_wgpu::{SolverOptions, wgpu_solver};

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes")
}

fn load(name: &str) -> SceneFile {
    SceneFile::load(&scenes_dir().join(name)).unwrap_or_else(|e| panic!("{e}"))
}

/// Every scene file under scenes/, sorted.
fn scene_files() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(scenes_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    v.sort();
    v
}

#[test]
fn every_scene_file_loads_and_builds() {
    let mut names = Vec::new();
    for path in scene_files() {
        let f = SceneFile::load(&path).unwrap_or_else(|e| panic!("{e}"));
        clothlab_core::build(&f.scene, &f.params).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(f.title.is_some(), "{} has no title", path.display());
        names.push(path.file_stem().unwrap().to_string_lossy().into_owned());
    }
    // The scenes the issue names.
    for want in ["thesis", "curtain", "tablecloth", "free-fall", "flag"] {
        assert!(names.iter().any(|n| n == want), "scenes/{want}.toml missing: {names:?}");
    }
    // The thesis's file is the built-in default scene (100 × 100) exactly.
    let thesis = load("thesis.toml");
    assert_eq!(thesis.scene, Scene::default());
    assert_eq!(thesis.params, SimParams::default());
}

/// Frames each scene file runs in the bits test: every kernel of a recipe runs in each
/// substep, and the second frame starts from what the first frame's end wrote (the normals
/// of `normals=frame`, which its forces read for the wind). 3 frames took 40 s on lavapipe.
const SCENE_FRAMES: u32 = 2;

/// Every scene file (a grid at most 32 × 32), with the serial CPU solver's state after
/// [`SCENE_FRAMES`]: computed once for the API rows. Where the scene has the contact
/// between triangles, the rayon solver is checked to compute the serial one's bits (its
/// sums are integer sums).
fn cpu_ends() -> &'static [(String, SceneFile, clothlab_core::ClothState)] {
    static ENDS: std::sync::OnceLock<Vec<(String, SceneFile, clothlab_core::ClothState)>> = std::sync::OnceLock::new();
    ENDS.get_or_init(|| {
        let scenes = scene_files();
        assert!(scenes.len() >= 20, "{scenes:?}");
        let run = |s: &mut dyn Solver| {
            for _ in 0..SCENE_FRAMES {
                s.step_frame().unwrap();
            }
            s.state().unwrap()
        };
        let mut ends = Vec::new();
        for path in &scenes {
            let mut f = SceneFile::load(path).unwrap_or_else(|e| panic!("{e}"));
            if !f.scene.cloth.is_mesh() {
                f.scene.cloth.n = f.scene.cloth.n.min(32);
            }
            let name = path.file_stem().unwrap().to_string_lossy().into_owned();
            let new = |exec| clothlab_cpu::CpuSolver::new(exec, f.scene.clone(), f.params.clone()).unwrap();
            let want = run(&mut new(Exec::Serial));
            if f.params.self_collision.triangles() {
                let got = run(&mut new(Exec::Parallel));
                assert!(got.pos == want.pos && got.vel == want.vel, "{name}: cpu-par is not cpu's bits");
            }
            ends.push((name, f, want));
        }
        ends
    })
}

clothlab_tests::per_api!(every_scene_file_computes_the_cpus_bits_on_the_optimized_recipe);

fn every_scene_file_computes_the_cpus_bits_on_the_optimized_recipe(api: Api) {
    // Every scene under scenes/ (together: every integrator a scene names, the floor,
    // spheres, boxes, capsules, bodies, moving colliders and pins, Coulomb friction,
    // self-collision, several cloths, meshes), 2 frames on each API's optimized recipe
    // against the serial CPU solver, a grid of more than 32 × 32 at 32 (the kernels are
    // the same at any n; at the files' sizes this test took 69 s on lavapipe): on
    // llvmpipe every position and velocity is the same
    // f32, which is what lets the physics tests run one API's optimized recipe
    // (`clothlab_tests::OPTIMIZED_ON`). Elsewhere other drivers round otherwise, and the
    // rollout bounds of the other tests apply: the difference is only printed.
    // Two frames: every kernel of a recipe runs in each substep, and the second frame
    // starts from what the first frame's end wrote (the normals of `normals=frame`, which
    // its forces read for the wind). 3 frames took 40 s on lavapipe.
    let mut differ = Vec::new();
    for (name, f, want) in cpu_ends() {
        let triangles = f.params.self_collision.triangles();
        let Some(gpu) = api.solver(Variant::OPTIMIZED, &f.scene, &f.params) else { continue };
        let adapter = gpu.adapter();
        let mut s = gpu.into_solver();
        for _ in 0..SCENE_FRAMES {
            s.step_frame().unwrap();
        }
        let got = s.state().unwrap();
        let off = |buf, a: &[[f32; 4]], b: &[[f32; 4]]| compare(name, buf, a, b, false, 0.0).max_abs;
        let (dx, dv) = (off("pos", &got.pos, &want.pos), off("vel", &got.vel, &want.vel));
        println!(
            "{name:18} {:7} {} particles: positions {dx:.1e} m, velocities {dv:.1e} m/s off",
            api.name(),
            got.pos.len()
        );
        // (Raw GL's contact between triangles is not yet the CPU's bits:
        // tests/tests/suite/tri_contact.rs.)
        let gl_triangles = triangles && api == Api::Gl;
        if adapter.contains("llvmpipe") && !gl_triangles && (got.pos != want.pos || got.vel != want.vel) {
            differ.push(format!("{name} on {}: {dx:.1e} m, {dv:.1e} m/s", api.name()));
        }
    }
    assert!(differ.is_empty(), "not the CPU's bits: {differ:?}");
}

clothlab_tests::per_backend!(the_free_falling_scene_falls_as_y0_minus_half_g_t_squared);

fn the_free_falling_scene_falls_as_y0_minus_half_g_t_squared(name: &str) {
    // The scene holds nothing and has no floor, drag or damping: every particle falls
    // freely, at the scene's own dt (1/960 s), 20 frames (0.33 s, 0.54 m of fall). The
    // velocity is set to the one at −dt/2 of a particle at rest at 0, for which Verlet (in
    // velocity form it keeps half-step velocities) is exact on a parabola; what remains is
    // f32 rounding. Each of the k substeps rounds y (≤ ½ ulp of |y| ≤ 2 m, 1.2e-7 m) and v
    // (≤ ½ ulp of |v| < 4 m/s, 2.4e-7 m/s, carried on for the rest of the fall): at most
    // k/2 · 2.4e-7 + k²/2 · 2.4e-7 · dt = 3.8e-5 + 1.3e-5 m. (When the velocity was kept
    // as x − x*, every rounding of y was carried on as velocity: 2 % of the fall at this
    // dt, and the test had to take 20 ms substeps.)
    let f = load("free-fall.toml");
    assert!(f.scene.floor_y.is_none() && f.scene.spheres.is_empty() && f.scene.boxes.is_empty());
    let scene = f.scene;
    let p = f.params;
    let (dt, g) = (p.dt(), p.gravity[1]);
    let frames = 20u32;
    let t = frames as f32 * p.frame_dt;
    let k = (frames * p.substeps) as f32;
    let ulp = 2.0f32.powi(-22); // of |y| in [2, 4): the cloth starts at y = 2
    let bound = k / 2.0 * ulp + k * k / 2.0 * 2.0f32.powi(-22) * dt;
    if let Some(mut s) = backend(name, &scene, &p) {
        let mut st = s.state().unwrap();
        let start = st.pos.clone();
        // The velocity at −dt/2 of a cloth at rest at 0: Verlet (in velocity form, it keeps
        // half-step velocities) is then exact on the parabola but for rounding.
        for q in st.vel.iter_mut() {
            *q = [0.0, -0.5 * g * dt, 0.0, 0.0];
        }
        s.set_state(&st).unwrap();
        for _ in 0..frames {
            s.step_frame().unwrap();
        }
        let end = s.state().unwrap().pos;
        let mut worst = 0.0f32;
        let mut sideways = 0.0f32;
        for (a, b) in start.iter().zip(&end) {
            let want = a[1] + 0.5 * g * t * t;
            worst = worst.max((b[1] - want).abs());
            sideways = sideways.max((b[0] - a[0]).abs().max((b[2] - a[2]).abs()));
        }
        println!(
            "{name:16} free fall: max |y − (y0 − ½gt²)| = {worst:.2e} m (bound {bound:.1e}), sideways {sideways:.2e} m"
        );
        assert!(worst <= bound, "{name}: {worst} m from y0 − ½gt² after {t} s (bound {bound})");
        // A uniform fall stretches no spring: nothing moves sideways but by rounding of
        // spring forces at rest length (a few ulps of x ≈ 0.5 m per substep).
        assert!(sideways < 20.0 * 2.0f32.powi(-24) * k, "{name}: moved {sideways} m sideways");
    }
}

/// Deepest a particle is inside any of `scene`'s boxes, m (0 when none is).
fn deepest_in_a_box(scene: &Scene, pos: &[[f32; 4]]) -> f32 {
    let mut deepest = 0.0f32;
    for b in &scene.boxes {
        for p in pos {
            let depth = (0..3).map(|k| (p[k] - b.min[k]).min(b.max[k] - p[k])).fold(f32::INFINITY, f32::min);
            deepest = deepest.max(depth);
        }
    }
    deepest
}

clothlab_tests::per_backend!(the_tablecloth_ends_outside_its_box_and_draped_over_it);

fn the_tablecloth_ends_outside_its_box_and_draped_over_it(name: &str) {
    // The tablecloth at n = 32, 90 frames (1.5 s: it lands on the table at 0.3 s and
    // drapes). No particle may be inside the box: collisions push particles out to the
    // margin every substep, so depth 0 (a particle exactly on a face counts as outside).
    let f = load("tablecloth.toml");
    let mut scene = f.scene.clone();
    scene.cloth.n = 32;
    let p = f.params.clone();
    assert_eq!(scene.boxes.len(), 1);
    let table_top = scene.boxes[0].max[1];
    if let Some(mut s) = backend(name, &scene, &p) {
        for _ in 0..90 {
            s.step_frame().unwrap();
        }
        let pos = s.state().unwrap().pos;
        let deepest = deepest_in_a_box(&scene, &pos);
        // Draped: the middle of the cloth rests on the table top, the corners hang below it.
        let n = 32;
        let middle = pos[(n / 2) * n + n / 2][1];
        let corner = pos[0][1];
        println!("{name:16} deepest in the box {deepest:.2e} m; middle at {middle:.3} m, a corner at {corner:.3} m");
        assert!(deepest <= 0.0, "{name}: a particle {deepest} m inside the box");
        // The middle rests at the table top plus the 1 cm collision margin (measured 0.810
        // m on every backend); 3 cm allows for the cloth still settling, and is far from
        // the 0.4 m it starts above the table.
        assert!((middle - table_top).abs() < 0.03, "{name}: the middle at {middle} m, the table top at {table_top} m");
        // The corner starts 0.4 m outside the table's edge and 0.4 m above it: hanging,
        // it is well below the top (measured 0.39–0.42 m, the top at 0.8 m); 0.1 m below
        // is a drape, not a cloth lying flat on the table or sliding off.
        assert!(corner < table_top - 0.1, "{name}: the corner at {corner} m does not hang over the edge");
    }
}

#[test]
fn with_a_box_in_the_scene_every_gpu_kernel_matches_its_twin_and_rollouts_follow_the_cpu() {
    // Kernel checks start from a cloth with particles put inside the box and under the
    // floor (engine::validate::KernelInput), so the box's collision code runs in them.
    // The rollout runs on a fresh solver (the checks leave their inputs in its buffers).
    let f = load("tablecloth.toml");
    let mut scene = f.scene.clone();
    scene.cloth.n = 33;
    let p = f.params.clone();
    for v in [Variant::NAIVE, Variant::OPTIMIZED] {
        let wgpu = || or_skip(wgpu_solver(v, scene.clone(), p.clone(), SolverOptions::default()), "wgpu");
        if let (Some(mut w), Some(mut fresh)) = (wgpu(), wgpu()) {
            let kernels = w.kernels();
            let label = format!("wgpu {}", v.label());
            assert_checks(&label, &validate_kernels_with(&mut w, &kernels, &scene, 5, &p).unwrap());
            assert_checks(&label, &[validate_rollout(&mut fresh, 20).unwrap()]);
        }
        let vulkan = || or_skip(vulkan_solver(v, scene.clone(), p.clone(), true, SolverOptions::default()), "vulkan");
        if let (Some(mut k), Some(mut fresh)) = (vulkan(), vulkan()) {
            let kernels = k.kernels();
            let label = format!("vk {}", v.label());
            assert_checks(&label, &validate_kernels_with(&mut k, &kernels, &scene, 5, &p).unwrap());
            assert_checks(&label, &[validate_rollout(&mut fresh, 20).unwrap()]);
            for s in [&k, &fresh] {
                let m = s.engine().take_validation_messages();
                assert!(m.is_empty(), "validation layer: {m:#?}");
            }
        }
    }
}

#[test]
fn the_kernel_checks_input_puts_particles_inside_every_collider_and_collide_takes_them_out() {
    // What makes the kernel checks above exercise the box: particles inside it (and in
    // the spheres, and under the floor) before, none in a collider after the CPU's collide.
    let mut scene = load("tablecloth.toml").scene;
    scene.cloth.n = 33;
    scene.spheres.push(clothlab_core::Sphere::new([1.5, 0.3, 0.0], 0.3));
    let input = clothlab_engine::validate::KernelInput::for_scene(&scene, 5, &SimParams::default()).unwrap();
    let inside_sphere = |pos: &[[f32; 4]]| {
        let s = scene.spheres[0];
        pos.iter().filter(|p| (0..3).map(|k| (p[k] - s.center[k]).powi(2)).sum::<f32>() < s.radius * s.radius).count()
    };
    let below_floor = |pos: &[[f32; 4]]| pos.iter().filter(|p| p[1] < 0.0).count();
    let (mut pos, mut vel) = (input.bufs.pos.clone(), input.bufs.vel.clone());
    let in_box = pos.iter().filter(|p| deepest_in_a_box(&scene, &[**p]) > 0.0).count();
    println!(
        "before collide: {in_box} in the box, {} in the sphere, {} under the floor",
        inside_sphere(&pos),
        below_floor(&pos)
    );
    assert!(in_box >= 2 && inside_sphere(&pos) >= 2 && below_floor(&pos) >= 2);
    let colliders = clothlab_cpu::Colliders::new(&scene.spheres, &scene.boxes);
    clothlab_cpu::collide(Exec::Serial, &input.p, colliders, &mut pos, &mut vel);
    assert_eq!(deepest_in_a_box(&scene, &pos), 0.0);
    assert_eq!(inside_sphere(&pos), 0);
    // The floor is the integration's (integrate, forces_integrate_collide): collide leaves it.
}
