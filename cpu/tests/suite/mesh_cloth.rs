//! A cloth made from a mesh on the CPU solvers: analytic cases (free fall, momentum), a
//! grid loaded as a mesh against the grid, a drape that stays outside its sphere, and the
//! mesh scenes and their refusals.

use std::path::PathBuf;
use std::sync::Arc;

use clothlab_core::mesh::{PlacedMesh, Placement, TriMesh, load_obj};
use clothlab_core::{Integrator, Pinning, Scene, SceneFile, SimParams, Solver, Sphere};
use clothlab_cpu::{CpuSolver, Exec};

fn scenes() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenes")
}

fn obj(name: &str) -> TriMesh {
    load_obj(&scenes().join("meshes").join(name)).unwrap_or_else(|e| panic!("{e}"))
}

/// A scene whose cloth is `mesh` placed by `placement`, with no colliders and no floor.
fn mesh_scene(mesh: &TriMesh, placement: Placement, pinning: Pinning) -> Scene {
    let mut scene =
        Scene { floor_y: None, spheres: Vec::new(), boxes: Vec::new(), motions: Vec::new(), ..Scene::default() };
    scene.cloth.mesh = Some("test.obj".into());
    scene.cloth.pinning = pinning;
    (scene.cloth.scale, scene.cloth.rotate_deg, scene.cloth.translate) =
        (placement.scale, placement.rotate_deg, placement.translate);
    scene.cloth.mesh_data = Some(Arc::new(PlacedMesh::new(mesh, &placement).unwrap()));
    scene
}

fn up(y: f32) -> Placement {
    Placement { translate: [0.0, y, 0.0], ..Placement::default() }
}

/// Free fall: every vertex of the round tablecloth (masses from 0.2 to 1.1 of the mean: its
/// rim is a staircase) falls as the integrator's recurrence says for a constant g, from
/// two heights, at two substep counts. A vertex whose force and mass disagreed would fall
/// at another rate and the springs would pull the cloth out of shape.
#[test]
fn a_mesh_falls_freely_as_the_recurrence_says() {
    let mesh = obj("tablecloth.obj");
    for integrator in Integrator::ALL {
        for (height, substeps) in [(2.0f32, 16u32), (50.0, 64)] {
            let scene = mesh_scene(&mesh, up(height), Pinning::None);
            let params = SimParams { integrator, substeps, damping: 0.0, air_drag: 0.0, ..SimParams::default() }
                .with_soft_springs();
            let mut solver = CpuSolver::new(Exec::Parallel, scene, params.clone()).unwrap();
            let start = solver.state().unwrap();
            // 5 frames: 80 and 320 substeps (10 frames took 22 s, implicit Euler's CG and
            // VBD's sweeps at 64 substeps 12.5 of them).
            let frames = 5;
            for _ in 0..frames {
                solver.step_frame().unwrap();
            }
            let end = solver.state().unwrap();
            let (g, dt, k) = (9.81f64, params.dt() as f64, (frames * substeps) as f64);
            let fall = match integrator {
                Integrator::Euler => g * dt * dt * k * (k - 1.0) / 2.0,
                Integrator::Rk2 | Integrator::Rk4 => 0.5 * g * (k * dt) * (k * dt),
                _ => g * dt * dt * k * (k + 1.0) / 2.0,
            };
            // Measured worst: 4.2e-6 m over 20 frames (at 50 m), 1.2e-6 over 10; 5e-5 m
            // is 4.3× below the smallest gap between two recurrences here (Euler's and
            // Verlet's, g·dt²·k: 2.1e-4 m at 64 substeps a frame over 5 frames, 8.5e-4 m
            // at 16), so the wrong integrator's fall fails.
            let tol = 5e-5;
            let worst =
                start.pos.iter().zip(&end.pos).map(|(a, b)| ((a[1] - b[1]) as f64 - fall).abs()).fold(0.0, f64::max);
            eprintln!("{integrator:?} {height} m {substeps}: fall {fall:.5} m, worst {worst:.2e} (tol {tol:.1e})");
            assert!(worst <= tol, "{integrator:?} from {height} m at {substeps} substeps: off by {worst:e} m");
        }
    }
}

/// With only internal forces (no gravity, drag, damping, floor or strain limiting), the
/// momentum Σ mᵢ vᵢ of a mesh with unequal masses does not change: the springs pull both
/// ends equally and each vertex turns its force into velocity by its own mass. If
/// `integrate` used the mean mass, the flag's momentum would drift by the springs' forces
/// times the masses' spread.
#[test]
fn momentum_with_only_internal_forces_is_kept() {
    let mesh = obj("flag_hole.obj");
    for integrator in [Integrator::Verlet, Integrator::Euler, Integrator::Rk2, Integrator::Rk4, Integrator::Xpbd] {
        let scene = mesh_scene(&mesh, up(1.0), Pinning::None);
        let params = SimParams {
            integrator,
            gravity: [0.0; 3],
            damping: 0.0,
            air_drag: 0.0,
            strain_iterations: 0,
            ..SimParams::default()
        }
        .with_soft_springs();
        let mut solver = CpuSolver::new(Exec::Serial, scene, params).unwrap();
        let mass = solver.topology().mesh.as_ref().unwrap().mass.clone();
        let mut state = solver.state().unwrap();
        // A velocity field that stretches and shears the flag: the springs work hard.
        for (p, v) in state.pos.iter().zip(&mut state.vel) {
            *v = [0.3 + 0.8 * p[1], -0.5 * p[0] + 0.2, (3.0 * p[0]).sin(), 0.0];
        }
        solver.set_state(&state).unwrap();
        let momentum = |s: &clothlab_core::ClothState| {
            let mut sum = [0.0f64; 3];
            for (m, v) in mass.iter().zip(&s.vel) {
                for c in 0..3 {
                    sum[c] += *m as f64 * v[c] as f64;
                }
            }
            sum
        };
        let scale: f64 =
            mass.iter().zip(&state.vel).map(|(m, v)| *m as f64 * (v[0].abs() + v[1].abs() + v[2].abs()) as f64).sum();
        let before = momentum(&state);
        for _ in 0..20 {
            solver.step_frame().unwrap();
        }
        let after = momentum(&solver.state().unwrap());
        let drift = (0..3).map(|c| (after[c] - before[c]).abs()).fold(0.0, f64::max) / scale;
        eprintln!("{integrator:?}: momentum drift {drift:.2e} of Σ m|v|");
        // f32 sums of forces of both signs: rounding only (measured ≤ 1.7e-8; with
        // `integrate` at the mean mass instead of the vertex's: 1.1e-3).
        assert!(drift < 1e-5, "{integrator:?}: momentum drifted by {drift:e} of Σ m|v|");
    }
}

/// The default scene's grid (n = 32, two pinned corners, three spheres, the floor) loaded
/// as a mesh (`grid_mesh`, the same triangles and vertex order) drapes where the grid does.
/// Not to the bit: a mesh has its edges (structural and one diagonal) and bending springs
/// across the edges where the grid has two diagonals and springs two apart, and its rim
/// vertices carry half a square's mass where the grid's carry a whole one.
#[test]
fn a_grid_loaded_as_a_mesh_drapes_where_the_grid_does() {
    let grid_scene = Scene::with_n(32);
    let scene = clothlab_core::cloth::grid_as_mesh(&grid_scene).unwrap();
    let params = SimParams::default();
    let mut grid = CpuSolver::new(Exec::Parallel, grid_scene, params.clone()).unwrap();
    let mut mesh = CpuSolver::new(Exec::Parallel, scene, params).unwrap();
    // The same particles at the same places, the same two held.
    let (a, b) = (grid.state().unwrap(), mesh.state().unwrap());
    for (p, q) in a.pos.iter().zip(&b.pos) {
        assert_eq!(p[..3], q[..3]);
        assert_eq!(p[3] == 0.0, q[3] == 0.0);
    }
    for _ in 0..180 {
        grid.step_frame().unwrap();
        mesh.step_frame().unwrap();
    }
    let (mean, max) =
        clothlab_core::cloth::mean_and_max_distance(&grid.state().unwrap().pos, &mesh.state().unwrap().pos);
    eprintln!("grid vs mesh after 3 s: mean {mean:.4} m, max {max:.4} m");
    // Measured: mean 2.4 cm, max 10.1 cm (the free corner's swing). The bounds are about
    // twice that: a cloth that fell differently (wrong masses, springs or pins) is off by
    // decimetres everywhere, while the two spring sets' honest difference stays at cm.
    assert!(mean < 0.05 && max < 0.2, "mean {mean} m, max {max} m");
}

/// The round tablecloth dropped on a sphere: after 3 s no vertex is inside the sphere
/// (the collision puts them at radius + margin; the strain limit after it may pull a
/// vertex back by a fraction of the margin).
#[test]
fn a_mesh_drape_stays_outside_its_sphere() {
    let mut scene = mesh_scene(&obj("tablecloth.obj"), up(1.2), Pinning::None);
    let sphere = Sphere::new([0.0, 0.6, 0.0], 0.45);
    (scene.spheres, scene.floor_y) = (vec![sphere], Some(0.0));
    let params = SimParams::default();
    let margin = params.collision_margin;
    let mut solver = CpuSolver::new(Exec::Parallel, scene, params).unwrap();
    for _ in 0..180 {
        solver.step_frame().unwrap();
    }
    let s = solver.state().unwrap();
    let c = glam::Vec3::from(sphere.center);
    let closest = s.pos.iter().map(|p| glam::Vec3::new(p[0], p[1], p[2]).distance(c)).fold(f32::INFINITY, f32::min);
    let top = s.pos.iter().map(|p| p[1]).fold(f32::MIN, f32::max);
    eprintln!("closest {closest:.4} m from the centre (radius {}), top {top:.3} m", sphere.radius);
    assert!(closest >= sphere.radius + 0.5 * margin, "a vertex {closest} m from the centre");
    // And it rests on the sphere: its top within 5 cm of the sphere's (measured 1.0 cm
    // above it: the margin and the cloth's sag between vertices); a cloth that fell through
    // or bounced off would be decimetres away.
    assert!((top - (sphere.center[1] + sphere.radius)).abs() < 0.05, "top at {top} m");
}

/// The three mesh scenes load with their meshes, pins and particle counts, and simulate on
/// both CPU solvers to the same bits (the rayon solver's gathers are the serial one's).
#[test]
fn the_mesh_scenes_load_and_run() {
    for (name, particles, pinned) in
        [("mesh-tablecloth.toml", 2813, 0), ("mesh-skirt.toml", 1536, 64), ("mesh-flag.toml", 2364, 41)]
    {
        let file = SceneFile::load(&scenes().join(name)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(file.scene.num_particles(), particles, "{name}");
        let mut serial = CpuSolver::new(Exec::Serial, file.scene.clone(), file.params.clone()).unwrap();
        let mut par = CpuSolver::new(Exec::Parallel, file.scene, file.params).unwrap();
        let held = serial.state().unwrap().pos.iter().filter(|p| p[3] == 0.0).count();
        assert_eq!(held, pinned, "{name}");
        for _ in 0..10 {
            serial.step_frame().unwrap();
            par.step_frame().unwrap();
        }
        let (a, b) = (serial.state().unwrap(), par.state().unwrap());
        assert_eq!(a.pos, b.pos, "{name}");
        assert!(a.pos.iter().flatten().all(|x| x.is_finite()), "{name}");
        assert!(serial.path().contains("a mesh runs its kernels"), "{}", serial.path());
    }
}

/// Every way a mesh scene can be wrong gets one line naming the problem.
#[test]
fn bad_mesh_scenes_are_refused_in_one_line() {
    let file = scenes().join("bad.toml");
    let file = file.to_str().unwrap();
    let cases = [
        ("[cloth]\nmesh = \"meshes/skirt.obj\"\nn = 32\n", "`cloth.n` is the grid's"),
        ("[cloth]\nmesh = \"meshes/skirt.obj\"\npinning = \"top-corners\"\n", "names grid points; a mesh takes"),
        ("[cloth]\npinning = { below_y = 1.0 }\n", "pins a mesh's vertices; a grid takes"),
        ("[cloth]\nmesh = \"meshes/none.obj\"\n", "none.obj: cannot read it"),
        (
            "[cloth]\nmesh = \"meshes/skirt.obj\"\npinning = { vertices = [3, 99999] }\n",
            "pinned vertex 99999 does not exist",
        ),
        ("[cloth]\nmesh = \"meshes/skirt.obj\"\npinning = { sideways = 1 }\n", "unknown field `sideways`"),
        ("[cloth]\nmesh = \"meshes/skirt.obj\"\nscale = [1.0, 0.0, 1.0]\n", "`cloth.scale`"),
        (
            "[cloth]\nmesh = \"meshes/skirt.obj\"\n[params]\nself_collision = true\nself_thickness = 0.03\n",
            "share no spring lie 0.0550 m apart at rest",
        ),
    ];
    for (text, want) in cases {
        // A refusal at load or, for what depends on the parameters, at build.
        let msg = match SceneFile::parse(text, file) {
            Err(e) => e.to_string(),
            Ok(f) => match CpuSolver::new(Exec::Serial, f.scene, f.params) {
                Err(e) => e.to_string(),
                Ok(_) => panic!("{text:?} was accepted"),
            },
        };
        assert!(msg.contains(want), "{text:?}: `{msg}` should say `{want}`");
        assert!(!msg.contains('\n'), "{text:?}: more than one line: {msg}");
    }
    // A bad OBJ file: its error with the file's line.
    let dir = std::env::temp_dir().join(format!("clothlab-mesh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n").unwrap();
    let scene = dir.join("s.toml");
    let msg = SceneFile::parse("[cloth]\nmesh = \"bad.obj\"\n", scene.to_str().unwrap()).unwrap_err().to_string();
    assert!(msg.contains("bad.obj: line 4: vertex index 7"), "{msg}");
    assert!(msg.contains("s.toml:2:"), "the scene file's line: {msg}");
    std::fs::remove_dir_all(&dir).ok();
}

/// XPBD on a mesh holds its constraints: the flag hung from its 41 pole vertices with the
/// strain limit off and one XPBD iteration a substep keeps its edges near their rest
/// lengths (median strain; measured 0.13 %, Verlet 0.20 %) while it swings down under
/// gravity. The median, not the maximum: the few edges beside the top pinned corner stretch
/// by about 110 % under XPBD and Verlet alike (a triangle mesh has one diagonal per quad,
/// nothing against shear across the other, so the free top edge hangs on them). A pass that
/// skipped springs would let the flag tear away from the pole (median strain far above 1 %).
#[test]
fn xpbd_holds_a_hanging_mesh_together() {
    let file = SceneFile::load(&scenes().join("mesh-flag.toml")).unwrap();
    let params = SimParams { integrator: Integrator::Xpbd, strain_iterations: 0, wind: [0.0; 3], ..file.params };
    let mut solver = CpuSolver::new(Exec::Parallel, file.scene, params).unwrap();
    let start = solver.state().unwrap();
    for _ in 0..60 {
        solver.step_frame().unwrap();
    }
    let end = solver.state().unwrap();
    let topo = solver.topology();
    let len = |p: &[[f32; 4]], a: u32, b: u32| {
        glam::Vec3::from_slice(&p[a as usize][..3]).distance(glam::Vec3::from_slice(&p[b as usize][..3]))
    };
    let mut strain: Vec<f32> = topo
        .springs
        .iter()
        .filter(|s| s.kind == clothlab_core::SpringKind::Structural as u32)
        .map(|s| len(&end.pos, s.a, s.b) / s.rest - 1.0)
        .collect();
    strain.sort_by(f32::total_cmp);
    let median = strain[strain.len() / 2];
    let drop = start.pos.iter().zip(&end.pos).map(|(a, b)| a[1] - b[1]).fold(0.0f32, f32::max);
    eprintln!("xpbd flag: median edge strain {median:.5}, largest drop {drop:.3} m");
    assert!(drop > 0.3, "the flag should swing down, dropped {drop} m");
    assert!(median.abs() < 0.01, "median edge strain {median}");
}

/// The strain limit holds a mesh's edges and only those: a vertex's row lists its edges
/// first (the row's head, which the strain limit and its counts walk) and its bending
/// springs after. Every spring of the list is in both its ends' rows; every head entry is
/// an edge and every entry past the head a bending spring.
#[test]
fn the_strain_limit_reads_the_edges_and_the_gather_every_spring() {
    use clothlab_core::grid::SpringKind;
    for name in ["mesh-skirt.toml", "mesh-flag.toml", "mesh-tablecloth.toml"] {
        let file = SceneFile::load(&scenes().join(name)).unwrap();
        let (_, topo) = clothlab_core::build(&file.scene, &file.params).unwrap();
        let mesh = topo.mesh.as_ref().unwrap();
        let (mut limited, mut found) = (0, 0);
        for v in 0..topo.num_particles() {
            let range = topo.slots.range(v);
            let head = topo.slots.head(v).len();
            for (s, slot) in topo.slots.row(v).iter().enumerate() {
                let edge = mesh.slot_kind[range.start + s] == SpringKind::Structural;
                assert_eq!(edge, s < head, "{name}: vertex {v} entry {s}: the head is its edges");
                assert!(slot.neighbor >= 0, "{name}: vertex {v} entry {s} empty or marked");
                limited += usize::from(s < head);
                found += usize::from(slot.other().is_some());
            }
        }
        let edges = topo.springs.iter().filter(|s| s.kind == SpringKind::Structural as u32).count();
        assert_eq!(limited, 2 * edges, "{name}: every edge limited from both ends");
        assert_eq!(found, 2 * topo.springs.len(), "{name}: every spring gathered at both ends");
    }
}

/// The strain limit holds an irregular mesh: the Delaunay cape (vertices of 1 to 8
/// triangles, rows of 3 to 16 springs), hung by its shoulders with no wind and no sphere,
/// its edges stretched by its weight. Measured (τ = 0.1): its longest edge at 0.216 with
/// the limit off and 0.1000 with 8 passes a substep (the passes aim at 0.95 τ, the springs
/// of the next substep pull back towards the limit). Bounds: past 1.8 τ without, within
/// 1.05 τ with.
#[test]
fn the_strain_limit_holds_a_hanging_irregular_mesh() {
    let file = SceneFile::load(&scenes().join("mesh-cape.toml")).unwrap();
    let mut scene = file.scene;
    scene.spheres.clear();
    let base = SimParams { wind: [0.0; 3], ..file.params };
    let max_edge_strain = |params: SimParams| {
        let mut solver = CpuSolver::new(Exec::Parallel, scene.clone(), params).unwrap();
        for _ in 0..60 {
            solver.step_frame().unwrap();
        }
        let end = solver.state().unwrap();
        let topo = solver.topology();
        let p = |k: u32| glam::Vec3::from_slice(&end.pos[k as usize][..3]);
        topo.springs
            .iter()
            .filter(|s| s.kind == clothlab_core::SpringKind::Structural as u32)
            .map(|s| p(s.a).distance(p(s.b)) / s.rest - 1.0)
            .fold(0.0f32, f32::max)
    };
    let tau = base.strain_limit;
    let free = max_edge_strain(SimParams { strain_iterations: 0, ..base.clone() });
    let held = max_edge_strain(SimParams { strain_iterations: 8, ..base.clone() });
    eprintln!(
        "cape hung by its shoulders: max edge strain {free:.4} without the limit, {held:.4} with 8 passes (τ {tau})"
    );
    assert!(free > 1.8 * tau, "without the limit the cape should stretch past 1.8τ: {free}");
    assert!(held < 1.05 * tau, "with 8 passes the cape's edges should stay within 1.05τ: {held}");
}
