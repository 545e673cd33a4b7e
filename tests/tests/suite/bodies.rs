//! Bodies: colliders from triangle meshes as distance fields (issue 45, `core::sdf`), on
//! every backend: the analytic sphere against the same sphere made of triangles, a patch
//! carried by a spinning body's friction, no particle deep inside a body, the GPU recipes
//! against the CPU twins, and bad bodies refused in one line.

use std::path::Path;

use clothlab_core::mesh::{Placement, load_obj};
use clothlab_core::scene::Pinning;
use clothlab_core::sdf::Body;
use clothlab_core::{Motion, Scene, SceneFile, SimParams, Solver, Sphere};
use clothlab_tests::{Api, assert_checks, backend, speed, still_air};

fn meshes() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/meshes")
}

/// The unit icosphere of `scenes/meshes` (1280 triangles) scaled to radius `r` about
/// `c`, as a body of `resolution` cells across, moved by `motion`.
fn icosphere(c: [f32; 3], r: f32, resolution: u32, motion: Motion) -> Body {
    let mesh = load_obj(&meshes().join("icosphere.obj")).unwrap();
    let placed = mesh.placed(&Placement { scale: [r; 3], rotate_deg: [0.0; 3], translate: c });
    Body::new(placed, resolution, None, Some(c), motion).unwrap()
}

/// Sphere radius, m, and its spin about z, rad/s.
const R: f32 = 0.5;
const OMEGA: f32 = 2.0;

/// A 2 cm patch of 4 × 4 particles 1 mm above the top of a body (an icosphere) spinning
/// about z: the analytic sphere's case of tests/tests/suite/motion.rs.
fn spinning_body() -> Scene {
    let mut s = Scene::with_n(4);
    s.cloth.size = 0.02;
    s.cloth.pinning = Pinning::None;
    let margin = SimParams::default().collision_margin;
    s.cloth.top_center = [0.0, 2.0 * R + margin + 1e-3, -0.01];
    s.floor_y = None;
    s.spheres.clear();
    s.bodies = vec![icosphere([0.0, R, 0.0], R, 32, Motion { spin: [0.0, 0.0, OMEGA], ..Motion::default() })];
    s
}

clothlab_tests::per_backend!(a_patch_on_a_spinning_body_moves_with_its_surface_when_it_sticks_and_not_when_it_slides);

fn a_patch_on_a_spinning_body_moves_with_its_surface_when_it_sticks_and_not_when_it_slides(name: &str) {
    // The icosphere's top vertex sits on the axis' normal plane at r: the patch rests on
    // the faces around it, whose field's zero level is within the faceting (≤ 3 mm at
    // 0.5 m, 1280 faces) of the sphere, plus the margin. With friction 1 each particle
    // leaves its contact at the surface's velocity there, ω·(distance from the axis):
    // within 2 % of ω (r + margin) (the faceting's 0.6 %, the patch's ±1 cm off the
    // plane, the field's interpolation).
    let margin = SimParams::default().collision_margin;
    let surface = (OMEGA * (R + margin)) as f64;
    if let Some(mut s) = backend(name, &spinning_body(), &still_air(1.0)) {
        for _ in 0..15 {
            s.step_frame().unwrap();
        }
        let v = speed(&s.state().unwrap());
        println!("{name:18} sticking: mean speed {v:.4} m/s (surface {surface:.4})");
        assert!((v - surface).abs() <= 0.02 * surface, "{name}: sticking patch at {v} m/s, the surface {surface}");
    }
    // Friction 0: only the normal part of the relative velocity goes; the patch stays on
    // the top, sliding off only as gravity pulls it down the faces (under 5 % of the
    // sticking speed after 0.25 s, as on the analytic sphere).
    if let Some(mut s) = backend(name, &spinning_body(), &still_air(0.0)) {
        for _ in 0..15 {
            s.step_frame().unwrap();
        }
        let v = speed(&s.state().unwrap());
        println!("{name:18} sliding: mean speed {v:.4} m/s");
        assert!(v <= 0.05 * surface, "{name}: frictionless patch dragged to {v} m/s");
    }
}

/// A closed box mesh (12 triangles) from `lo` to `hi`.
fn box_mesh(lo: [f32; 3], hi: [f32; 3]) -> clothlab_core::mesh::TriMesh {
    let positions = (0..8).map(|k| [0, 1, 2].map(|a| if k >> a & 1 == 1 { hi[a] } else { lo[a] })).collect();
    // Counter-clockwise seen from outside: -x, +x, -y, +y, -z, +z.
    let triangles = vec![
        [0, 4, 6],
        [0, 6, 2],
        [1, 3, 7],
        [1, 7, 5],
        [0, 1, 5],
        [0, 5, 4],
        [2, 6, 7],
        [2, 7, 3],
        [0, 2, 3],
        [0, 3, 1],
        [4, 5, 7],
        [4, 7, 6],
    ];
    clothlab_core::mesh::TriMesh { positions, uvs: None, triangles }
}

clothlab_tests::per_backend!(a_patch_on_a_body_turned_by_keys_moves_at_the_keys_rate);

fn a_patch_on_a_body_turned_by_keys_moves_at_the_keys_rate(name: &str) {
    use clothlab_core::Key;
    // A 1 m × 0.2 m × 1 m box body turned by keys 0 → 90° about y in 1 s (linear: ω =
    // π/2 rad/s about its centre); a 2 cm patch lies on its top 0.3 m from the axis. With
    // friction 1 the contacts give it the surface's velocity ω × (x − pivot): speed
    // ω·0.3 m at 0.25 s, within 0.5 % (the patch spans ±1 cm about 0.3 m, its mean
    // distance from the axis 0.3002 m; measured 0.06 % over); with friction 0 it does not
    // follow (under 5 %: nothing but the flat top's normal acts on it).
    let margin = SimParams::default().collision_margin;
    let turn = Motion {
        keys: vec![Key::new(0.0, [0.0; 3]), Key { rotate_deg: [0.0, 90.0, 0.0], ..Key::new(1.0, [0.0; 3]) }],
        ..Motion::default()
    };
    let mut sc = Scene::with_n(4);
    sc.cloth.size = 0.02;
    sc.cloth.pinning = Pinning::None;
    sc.cloth.top_center = [0.3, 0.2 + margin + 1e-3, -0.01];
    sc.floor_y = None;
    sc.spheres.clear();
    sc.bodies = vec![Body::new(box_mesh([-0.5, 0.0, -0.5], [0.5, 0.2, 0.5]), 32, None, None, turn).unwrap()];
    let want = std::f64::consts::FRAC_PI_2 * 0.3;
    for (friction, sticks) in [(1.0, true), (0.0, false)] {
        if let Some(mut s) = backend(name, &sc, &still_air(friction)) {
            for _ in 0..15 {
                s.step_frame().unwrap();
            }
            let v = speed(&s.state().unwrap());
            println!("{name:18} friction {friction}: mean speed {v:.4} m/s (the surface {want:.4})");
            if sticks {
                assert!((v - want).abs() <= 0.005 * want, "{name}: {v} m/s, the surface {want}");
            } else {
                assert!(v <= 0.05 * want, "{name}: a frictionless patch dragged to {v} m/s");
            }
        }
    }
}

/// A 32 × 32 cloth dropped from 0.3 m onto a sphere of radius 0.45 on the floor, the
/// sphere analytic or an icosphere body of `resolution` cells across.
fn drape(body: Option<u32>) -> Scene {
    let mut s = Scene::with_n(32);
    s.cloth.size = 1.4;
    s.cloth.pinning = Pinning::None;
    s.cloth.top_center = [0.0, 1.2, -0.7];
    let (c, r) = ([0.0, 0.45, 0.0], 0.45);
    match body {
        None => s.spheres = vec![Sphere::new(c, r)],
        Some(res) => {
            s.spheres.clear();
            s.bodies = vec![icosphere(c, r, res, Motion::default())];
        }
    }
    s
}

clothlab_tests::per_backend!(an_icosphere_body_drapes_a_cloth_as_the_sphere_does_and_holds_it_outside);

fn an_icosphere_body_drapes_a_cloth_as_the_sphere_does_and_holds_it_outside(name: &str) {
    let params = SimParams::default();
    let run = |scene: &Scene, frames: u32| {
        let mut s = clothlab_cpu::CpuSolver::new(clothlab_cpu::Exec::Serial, scene.clone(), params.clone()).unwrap();
        for _ in 0..frames {
            s.step_frame().unwrap();
        }
        s.state().unwrap()
    };
    // After 20 frames (the cloth landed 0.08 s before and lies over the top third of the
    // sphere), particle by particle against the analytic sphere's drape. The difference is
    // the field's: its trilinear interpolation of the distance (an error growing with the
    // cell h) over the faceted sphere (≤ 3 mm from it): measured 0.25 h at 24 and at 48
    // cells; bound 0.3 h + 2 mm, and it must shrink as the cells do. (Later the folds
    // choose their sides from differences this small, and particles part by decimetres: a
    // drape is not compared pointwise after it folds.)
    let sphere = run(&drape(None), 20);
    let mut errors = Vec::new();
    for res in [24u32, 48] {
        let h = 0.9 / res as f64;
        let body = run(&drape(Some(res)), 20);
        let worst = sphere
            .pos
            .iter()
            .zip(&body.pos)
            .map(|(a, b)| (0..3).map(|k| ((a[k] - b[k]) as f64).powi(2)).sum::<f64>().sqrt())
            .fold(0.0, f64::max);
        println!("resolution {res} (h {h:.4} m): farthest particle {worst:.4} m from the analytic drape");
        assert!(worst <= 0.3 * h + 0.002, "resolution {res}: the drape {worst} m from the sphere's");
        errors.push(worst);
    }
    assert!(errors[1] < 0.7 * errors[0], "finer cells, no closer drape: {errors:?}");
    // Every backend, 40 frames (folded over the sphere): no particle closer to the body
    // than the margin less 2 mm. The contacts leave each at φ ≥ margin (pushed along the
    // field's gradient to its margin level); the strain passes after them could pull one
    // back in where the cloth wraps round (measured: none, the deepest at the margin).
    let scene = drape(Some(32));
    if let Some(mut s) = backend(name, &scene, &params) {
        for _ in 0..40 {
            s.step_frame().unwrap();
        }
        let st = s.state().unwrap();
        let deepest = st
            .pos
            .iter()
            .filter_map(|p| scene.bodies[0].distance([p[0], p[1], p[2]], s.time()))
            .fold(f32::INFINITY, f32::min);
        println!("{name:18} deepest particle φ = {deepest:.4} m");
        let margin = params.collision_margin;
        assert!(deepest >= margin - 2e-3, "{name}: a particle at φ = {deepest} m, the margin {margin}");
    }
}

#[test]
fn every_gpu_recipe_and_the_cpu_engine_follow_the_cpu_with_a_turning_body() {
    // The contacts sample the field in the twins' order: the optimized recipes compute
    // the CPU solver's bits on llvmpipe with a body turning under the cloth (0 m over 12
    // frames); the kernel checks sink particles half a cell behind the body's triangles.
    let mut sc = drape(Some(32));
    sc.bodies[0].motion = Motion { spin: [0.0, 2.0, 0.0], velocity: [0.1, 0.0, 0.0], ..Motion::default() };
    sc.cloth.top_center[1] = 0.95;
    let params = SimParams::default();
    let checks = clothlab_tests::optimized_kernel_checks(&sc, &params, 0x5d);
    assert!(checks.iter().any(|c| c.what.contains("collide")), "no check of a collide kernel");
    assert_checks("bodies", &checks);
    clothlab_tests::assert_rollouts(clothlab_tests::optimized_rollout_solvers(&sc, &params), 12);
}

#[test]
fn the_kernel_checks_put_particles_into_the_body() {
    // What the twins' comparison is worth: the disturbed input has particles inside the
    // body, and the collide twin moves them out (a check of nothing would pass too).
    let sc = drape(Some(32));
    let params = SimParams::default();
    let input = clothlab_engine::validate::KernelInput::for_scene(&sc, 0x5d, &params).unwrap();
    let body = &sc.bodies[0];
    let inside = |pos: &[[f32; 4]]| {
        pos.iter().filter(|p| body.distance([p[0], p[1], p[2]], 0.0).is_some_and(|d| d < 0.0)).count()
    };
    let before = inside(&input.bufs.pos);
    let mut b = input.bufs.clone();
    let k = clothlab_engine::kernels::COLLIDE.plain();
    input.engine.run(&[clothlab_engine::recipe::Command::Dispatch(k)], &input.p, 0, &mut b);
    let after = inside(&b.pos);
    println!("particles inside the body: {before} before collide, {after} after");
    assert!(before >= 3, "only {before} particles sunk into the body");
    assert_eq!(after, 0, "collide left particles inside the body");
}

#[test]
fn bad_bodies_are_refused_in_one_line() {
    let dir = std::env::temp_dir().join(format!("clothlab-bodies-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(meshes().join("icosphere.obj"), dir.join("ball.obj")).unwrap();
    std::fs::write(dir.join("quad.obj"), "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nf 1 3 2\nf 1 4 3\n").unwrap();
    std::fs::write(dir.join("nan.obj"), "v 0 0 0\nv nan 0 0\nv 1 0 1\nf 1 2 3\n").unwrap();
    let file = |bodies: &str| {
        format!(
            "[cloth]\nn = 8\nsize = 1.0\ntop_center = [0, 2, 0]\npinning = \"none\"\n{bodies}[params]\nsubsteps = 4\n"
        )
    };
    let cases = [
        ("[[bodies]]\nmesh = \"missing.obj\"\n", "missing.obj", Some(7)),
        ("[[bodies]]\nmesh = \"quad.obj\"\n", "give its thickness", Some(7)),
        ("[[bodies]]\nmesh = \"ball.obj\"\nthickness = 0.01\n", "closed", Some(7)),
        ("[[bodies]]\nmesh = \"quad.obj\"\nthickness = -1\n", "thickness", Some(7)),
        ("[[bodies]]\nmesh = \"nan.obj\"\n", "nan.obj", Some(7)),
        ("[[bodies]]\nmesh = \"ball.obj\"\nresolution = 4\n", "from 8 to 256", Some(7)),
        ("[[bodies]]\nmesh = \"ball.obj\"\nscale = [0, 1, 1]\n", "bodies[0].scale", None),
        ("[[bodies]]\nmesh = \"ball.obj\"\nmotion = { spin = [0, nan, 0] }\n", "bodies[0].motion.spin", None),
        // 100 rad/s at 1 m in a substep of 1/240 s: 0.4 m, more than two cells (6 cm).
        ("[[bodies]]\nmesh = \"ball.obj\"\nresolution = 32\nmotion = { spin = [0, 100, 0] }\n", "2 cells", None),
        ("[[bodies]]\nmesh = \"ball.obj\"\ncolour = 1\n", "unknown field", Some(8)),
    ];
    let path = dir.join("bad.toml");
    for (bodies, expect, line) in cases {
        std::fs::write(&path, file(bodies)).unwrap();
        let e = SceneFile::load(&path).expect_err(expect);
        let msg = e.to_string();
        println!("{msg}");
        assert!(msg.contains(expect) && !msg.contains('\n'), "{expect}: {msg}");
        if let Some(l) = line {
            assert_eq!(e.at.map(|a| a.0), Some(l), "{msg}");
        }
    }
    // Five bodies: one more than a scene holds.
    let mut s = drape(Some(16));
    s.bodies = vec![s.bodies[0].clone(); 5];
    let e = s.validate().unwrap_err().to_string();
    assert!(e.contains("at most 4 bodies"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `optimized` with `sdf=image`: the bodies' fields in a 3-D image the texture unit
/// interpolates.
fn image_spec() -> clothlab_engine::VariantSpec {
    clothlab_engine::VariantSpec::parse("optimized", &["sdf=image".into()]).unwrap()
}

clothlab_tests::per_api!(the_fields_in_an_image_drape_the_cloth_as_the_sphere_does_within_the_filters_precision);

fn the_fields_in_an_image_drape_the_cloth_as_the_sphere_does_within_the_filters_precision(api: Api) {
    let params = SimParams::default();
    // Physics first: the icosphere at 48 cells sampled by the texture unit drapes the
    // cloth as the analytic sphere does, within the storage path's bound (0.3 h + 2 mm:
    // the field's interpolation and the faceting; the filter's weights add at most
    // 3 h·2^-(bits+1), 0.094 h at the 4 bits Vulkan allows), on wgpu, Vulkan and GL.
    let h = 0.9 / 48.0;
    let mut sphere = clothlab_cpu::CpuSolver::new(clothlab_cpu::Exec::Serial, drape(None), params.clone()).unwrap();
    for _ in 0..20 {
        sphere.step_frame().unwrap();
    }
    let a = sphere.state().unwrap();
    if let Some(mut s) = api.solver(image_spec(), &drape(Some(48)), &params) {
        for _ in 0..20 {
            s.step_frame().unwrap();
        }
        let b = s.state().unwrap();
        let worst = a
            .pos
            .iter()
            .zip(&b.pos)
            .map(|(p, q)| (0..3).map(|k| ((p[k] - q[k]) as f64).powi(2)).sum::<f64>().sqrt())
            .fold(0.0, f64::max);
        println!("{api:7} sdf=image at 48 cells (h {h:.4} m): farthest particle {worst:.4} m from the analytic drape");
        assert!(worst <= 0.3 * h + 0.002, "{api}: the image's drape {worst} m from the sphere's");
    }
    // Its kernels against the twins (which interpolate the stored values themselves):
    // within validate's bound for the image (`sdf_image_bound`: 0.1 h), a turning, sliding
    // body under the cloth as above; and 12 frames rolled out within it.
    let mut sc = drape(Some(32));
    sc.bodies[0].motion = Motion { spin: [0.0, 2.0, 0.0], velocity: [0.1, 0.0, 0.0], ..Motion::default() };
    sc.cloth.top_center[1] = 0.95;
    let Some(mut k) = api.solver(image_spec(), &sc, &params) else { return };
    let kernels = k.recipe_kernels();
    let checks = clothlab_engine::validate::validate_kernels_with(k.runner(), &kernels, &sc, 0x5d, &params).unwrap();
    clothlab_tests::assert_api_clean(&mut *k);
    assert!(checks.iter().any(|c| c.what.contains("_si")), "{api}: no kernel samples the image");
    assert_checks(&format!("{api} sdf=image"), &checks);
    let bound = clothlab_engine::validate::sdf_image_bound(&sc);
    if let Some(s) = api.solver(image_spec(), &sc, &params) {
        let mut s = s.into_solver();
        let mut c = clothlab_cpu::validate::validate_rollout(&mut *s, 12).unwrap();
        c.bound = c.bound.max(bound);
        println!("{api:7} sdf=image rollout: {:.2e} m (bound {:.2e})", c.max_abs, c.bound);
        assert!(c.passed(), "{api}: the image's rollout {} m from the CPU's, bound {}", c.max_abs, c.bound);
    }
}

clothlab_tests::per_api!(a_patch_on_a_spinning_body_in_an_image_moves_with_its_surface);

fn a_patch_on_a_spinning_body_in_an_image_moves_with_its_surface(api: Api) {
    // The spinning icosphere of the first test, sampled by the texture unit: the patch
    // moves at ω (r + margin) within the same 2 % (φ through the filter, the push along
    // the interpolant's gradient as through storage), on every API.
    let margin = SimParams::default().collision_margin;
    let surface = (OMEGA * (R + margin)) as f64;
    if let Some(mut s) = api.solver(image_spec(), &spinning_body(), &still_air(1.0)) {
        for _ in 0..15 {
            s.step_frame().unwrap();
        }
        let v = speed(&s.state().unwrap());
        println!("{api:7} sdf=image sticking: mean speed {v:.4} m/s (surface {surface:.4})");
        assert!((v - surface).abs() <= 0.02 * surface, "{api}: sticking patch at {v} m/s, the surface {surface}");
    }
}

clothlab_tests::per_api!(a_scene_without_bodies_runs_the_image_switch_as_storage_does);

fn a_scene_without_bodies_runs_the_image_switch_as_storage_does(api: Api) {
    // No bodies: the image is one texel the kernels never sample (the loop over bodies is
    // empty), so the recipe computes the storage recipe's bits on every API.
    let sc = Scene::with_n(24);
    let p = SimParams::default();
    let storage = api.solver(clothlab_engine::Variant::OPTIMIZED, &sc, &p);
    if let (Some(mut a), Some(mut b)) = (api.solver(image_spec(), &sc, &p), storage) {
        for _ in 0..4 {
            a.step_frame().unwrap();
            b.step_frame().unwrap();
        }
        let (a, b) = (a.state().unwrap(), b.state().unwrap());
        assert_eq!(a.pos, b.pos, "{api}: sdf=image without bodies changed the cloth");
    }
}
