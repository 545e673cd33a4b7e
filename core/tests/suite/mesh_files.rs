//! The mesh scenes' OBJ files (scenes/meshes, written by make_meshes.py and
//! make_irregular.py) load, pass every
//! check, and hold what their script says: areas against the shapes they approximate,
//! the skirt's ring closed at its seam; and glTF files another tool wrote (tests/data).

use std::collections::HashMap;
use std::path::PathBuf;

use clothlab_core::mesh::{MeshSprings, TriMesh, load_obj};

fn load(name: &str) -> TriMesh {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenes/meshes").join(name);
    load_obj(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// Edges in exactly one triangle.
fn boundary_edges(m: &TriMesh) -> usize {
    let mut count: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &m.triangles {
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    count.values().filter(|c| **c == 1).count()
}

#[test]
fn the_tablecloth_is_a_disc() {
    let m = load("tablecloth.obj");
    assert!(m.uvs.is_some());
    // The lattice's quads wholly inside r = 0.9 m: the disc less a boundary strip of about
    // one spacing (0.03 m) × the circumference, 0.17 of its 2.54 m².
    let disc = std::f32::consts::PI * 0.9 * 0.9;
    assert!(m.area() > 0.88 * disc && m.area() < disc, "{} of {disc}", m.area());
    // Every vertex within the radius, and 12 springs (6 edges, 6 bends) at interior vertices.
    assert!(m.positions.iter().all(|p| p[0].hypot(p[2]) <= 0.9 + 1e-5));
    let s = MeshSprings::build(&m).unwrap();
    assert_eq!(s.slots.iter().map(Vec::len).max(), Some(12));
}

#[test]
fn the_skirt_is_a_closed_ring() {
    let m = load("skirt.obj");
    // A frustum of radii 0.35 and 0.55 m, 0.6 m tall: π (r1 + r2) · slant = 1.788 m²;
    // 64 flat panels around lose cos(π/64) (0.1 %).
    let want = std::f32::consts::PI * 0.9 * 0.6f32.hypot(0.2);
    assert!((m.area() / want - 1.0).abs() < 0.005, "{} of {want}", m.area());
    // Only the waist and the hem are open: 64 edges each; the seam is closed.
    assert_eq!(boundary_edges(&m), 128);
    // Normals point outwards: the first triangle's normal has a positive radial part.
    let [a, b, c] = m.triangles[0].map(|i| glam::Vec3::from(m.positions[i as usize]));
    let n = (b - a).cross(c - a);
    let radial = glam::Vec3::new(a.x, 0.0, a.z);
    assert!(n.dot(radial) > 0.0, "{n:?}");
}

#[test]
fn the_flag_has_its_hole() {
    let m = load("flag_hole.obj");
    // 1.5 × 1 m less a hole of radius 0.18 m (0.102 m²), cut by whole quads.
    let want = 1.5 - std::f32::consts::PI * 0.18 * 0.18;
    assert!((m.area() / want - 1.0).abs() < 0.02, "{} of {want}", m.area());
    // Two boundaries: the outline (2 × (60 + 40) edges) and the hole's.
    let outline = 2 * (60 + 40);
    assert!(boundary_edges(&m) > outline + 20, "{}", boundary_edges(&m));
    // No vertex inside the hole but those on its quads' corners.
    assert!(m.positions.iter().all(|p| (p[0] - 0.9).hypot(p[1] - 0.5) > 0.18 - 0.025 * 1.5));
}

/// Triangles at each vertex.
fn triangles_at(m: &TriMesh) -> Vec<usize> {
    let mut count = vec![0; m.positions.len()];
    m.triangles.iter().flatten().for_each(|&v| count[v as usize] += 1);
    count
}

/// Every triangle's normal has a positive part along `up` (the script's winding).
fn all_facing(m: &TriMesh, up: glam::Vec3) -> bool {
    m.triangles.iter().all(|t| {
        let [a, b, c] = t.map(|i| glam::Vec3::from(m.positions[i as usize]));
        (b - a).cross(c - a).dot(up) > 0.0
    })
}

#[test]
fn the_fan_is_a_disc_with_a_vertex_of_64_triangles() {
    let m = load("fan.obj");
    m.check().unwrap();
    // A 64-gon of circumradius 0.8 m: (64/2) r² sin(2π/64) = 2.0074 m², the disc's 99.8 %.
    let want = 32.0 * 0.64 * (std::f32::consts::TAU / 64.0).sin();
    assert!((m.area() / want - 1.0).abs() < 1e-4, "{} of {want}", m.area());
    let count = triangles_at(&m);
    assert_eq!(count[0], 64, "the centre");
    assert_eq!(count.iter().min(), Some(&3), "the first ring's vertices (and the rim's)");
    assert!(all_facing(&m, glam::Vec3::Y), "normals up (+y)");
    // The centre's row: 64 edges (its head), then 64 bending springs (across each edge of
    // the first ring, to the second ring's vertex opposite it).
    let s = MeshSprings::build(&m).unwrap();
    assert_eq!(s.slots[0].iter().filter(|&&k| s.is_edge(k)).count(), 64);
    assert_eq!(s.slots[0].len(), 128);
    assert_eq!(boundary_edges(&m), 64, "the rim");
}

#[test]
fn the_cape_is_an_irregular_delaunay_sheet() {
    let m = load("cape.obj");
    m.check().unwrap();
    let count = triangles_at(&m);
    let interior: Vec<usize> = count.iter().copied().filter(|&c| c >= 3).collect();
    // Delaunay of jittered points: interior vertices of 4 to 8 triangles, not the
    // lattice's 6 everywhere (over a fifth of them differ).
    assert!(count.iter().max().copied() >= Some(8), "{:?}", count.iter().max());
    let off = interior.iter().filter(|&&c| c != 6).count();
    assert!(off * 5 > interior.len(), "{off} of {} interior vertices off valence 6", interior.len());
    assert!(all_facing(&m, glam::Vec3::Z), "normals towards +z");
    // A trapezoid 0.5 → 1.2 m wide, 0.9 m tall, and a hem bowed 0.1 m: 0.765 + 0.08 m².
    let want = 0.5 * (0.5 + 1.2) * 0.9 + 2.0 / 3.0 * 1.2 * 0.1;
    assert!((m.area() / want - 1.0).abs() < 0.02, "{} of {want}", m.area());
}

/// A file of core/tests/data (written by another tool: make_foreign.py, trimesh 4).
fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

#[test]
fn gltf_files_another_tool_wrote_load_and_bad_ones_are_refused_in_one_line() {
    use clothlab_core::mesh::{PlacedMesh, Placement, load_gltf};
    // trimesh's .glb and its .gltf with an embedded buffer: the same 9 × 9 sheet of
    // 0.8 m (81 vertices, 128 triangles, u32 indices, no uvs) in trimesh's vertex order.
    let glb = load_gltf(&data("trimesh_sheet.glb"), None).unwrap_or_else(|e| panic!("{e}"));
    let gltf = load_gltf(&data("trimesh_sheet.gltf"), Some("sheet")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(glb, gltf, "the two encodings of one mesh");
    assert_eq!((glb.positions.len(), glb.triangles.len(), glb.uvs.is_some()), (81, 128, false));
    // 0.64 m² to f32 rounding of 128 triangle areas (relative 1e-5 covers it).
    assert!((glb.area() - 0.64).abs() < 0.64e-5, "area {}", glb.area());
    assert_eq!(glb.positions[10], [-0.3, 0.0, 0.1], "vertex (1, 1) where the script put it");
    // It is a cloth: placed and built, every vertex kept, its normals up (the winding
    // trimesh kept is the script's counter-clockwise one, seen from +y).
    let placed = PlacedMesh::new(&glb, &Placement::default()).unwrap();
    assert_eq!(placed.dropped(), 0);
    let [a, b, c] = glb.triangles[0].map(|v| glam::Vec3::from(glb.positions[v as usize]));
    assert!((b - a).cross(c - a).y > 0.0);
    // A .glb cut in half and a name the file does not have: one line each.
    for (file, name, want) in [
        ("truncated.glb", None, "not a glTF file clothlab can read"),
        ("trimesh_sheet.glb", Some("cape"), "no mesh named `cape` (it has `sheet`)"),
    ] {
        let e = load_gltf(&data(file), name).unwrap_err().to_string();
        assert!(e.contains(file) && e.contains(want), "{file}: {e}");
        assert!(!e.contains('\n'), "{e}");
    }
    // A union jack (8 triangles and 8 edges at every other interior vertex, more than a
    // grid's fixed table holds; refused before the compressed rows) loads and builds.
    let jack = load_gltf(&data("trimesh_unionjack.glb"), None).unwrap();
    let placed = PlacedMesh::new(&jack, &Placement::default()).unwrap();
    let most = placed.springs.slots.iter().map(|s| s.iter().filter(|&&k| placed.springs.is_edge(k)).count()).max();
    assert_eq!(most, Some(8), "edges at the union jack's star vertices");
}
