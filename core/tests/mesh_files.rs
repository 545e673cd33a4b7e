//! The mesh scenes' OBJ files (scenes/meshes, written by make_meshes.py) load, pass every
//! check, and hold what their script says: areas against the shapes they approximate,
//! the skirt's ring closed at its seam.

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
    // Every vertex within the radius, and the table full at interior vertices.
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
