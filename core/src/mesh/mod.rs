//! Cloth from a triangle mesh: reading an OBJ file, refusing meshes a cloth cannot be,
//! and the mesh's springs. Every solver and GPU API runs a mesh cloth as it runs a grid.
//!
//! The reader keeps the file's vertex numbering (`v` lines in order, from 0), so a list of
//! pinned vertices taken from a modelling tool means what it says, and a vertex no face
//! uses is found and refused. tobj, the usual crate, renumbers vertices by first use and
//! drops unused ones, so both would be lost; the part of OBJ a cloth needs (`v`, `vt`,
//! `f` with `v`, `v/vt`, `v//vn`, `v/vt/vn` and negative indices, polygons as fans) is
//! read here, everything else (`vn`, `o`, `g`, `s`, `usemtl`, `mtllib`, …) skipped.
//!
//! A mesh is checked before anything is built from it ([`TriMesh::check`]): every index
//! in range, coordinates finite, no degenerate or repeated triangle, no vertex outside
//! every triangle, every edge in at most two triangles (a manifold, with boundary) whose
//! windings agree. A vertex may have any number of triangles (the solvers' tables of a
//! mesh are compressed rows, `tables::Rows`). Each refusal is one line naming the vertex,
//! edge or triangle.
//!
//! The springs ([`MeshSprings`]): structural along every edge, bending across every
//! interior edge (between the two vertices opposite it), rest lengths from the mesh. In a
//! vertex's row the edges come first (the row's head, which the strain limit holds), the
//! bending springs after them.
//!
//! Here: the mesh and its checks; `read`: OBJ and glTF files (and OBJ out); `place`: a
//! mesh in the scene (placement, pins, masses, tethers, a scene's cloths as parts);
//! `springs`: the springs.

use std::collections::HashMap;

use thiserror::Error;

mod place;
mod read;
mod springs;

pub use place::{ClothPart, MeshPinning, PlacedMesh, Placement, grid_mesh, planar_uvs};
pub use read::{MeshFileError, load_gltf, load_mesh, load_obj, parse_obj, to_obj};
pub use springs::MeshSprings;

/// The largest OBJ file read, bytes.
pub const MAX_MESH_BYTES: u64 = 256 << 20;

/// The most vertices a cloth mesh may have (as many particles as a 2048 × 2048 grid).
pub const MAX_MESH_VERTICES: usize = 2048 * 2048;

/// The farthest a mesh's vertex may lie from the origin once placed, m (as a grid's top
/// centre): squared distances stay far from f32's overflow, and a position there still
/// resolves 1 mm.
pub const MAX_COORDINATE: f32 = 1e4;

/// The shortest edge, in spacings of f32 values at the mesh's largest coordinate: a
/// spring's length is then known to 0.1 %, so its force is not rounding noise.
pub const SPRING_ULPS: f32 = 1024.0;

/// The most springs (edges and bending springs) a mesh may have per vertex, on average:
/// XPBD keeps a mesh's λ, a word per spring, in two of the particles' four-word scratch
/// buffers. A sheet has fewer than 6 (Euler: E ≤ 3V edges, a bending spring per interior
/// edge), whatever its valences; only a surface of many handles has more.
pub const MAX_SPRINGS_PER_VERTEX: usize = 8;

/// A triangle mesh as read: positions, optional texture coordinates per vertex, and
/// counter-clockwise triangles (their normals point to the side seen counter-clockwise).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TriMesh {
    /// Vertex positions, m (before placement).
    pub positions: Vec<[f32; 3]>,
    /// A texture coordinate per vertex, when the file gives every face-vertex one (at a
    /// seam, a vertex keeps the first it is given).
    pub uvs: Option<Vec<[f32; 2]>>,
    /// Triangles, indices into `positions`.
    pub triangles: Vec<[u32; 3]>,
}

/// Why a mesh cannot be a cloth: one line.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MeshError {
    /// The file could not be read.
    #[error("cannot read it: {0}")]
    Read(String),
    /// The file is larger than [`MAX_MESH_BYTES`].
    #[error("{size} bytes, more than the {max} a mesh file may have")]
    TooBig {
        /// Its size.
        size: u64,
        /// The limit.
        max: u64,
    },
    /// A line the reader does not understand.
    #[error("line {line}: {what}")]
    Syntax {
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        what: String,
    },
    /// No triangles.
    #[error("no triangles: a cloth mesh needs faces (`f` lines)")]
    Empty,
    /// Too many vertices.
    #[error("{count} vertices, more than the {max} a cloth may have")]
    TooManyVertices {
        /// Vertices in the file.
        count: usize,
        /// The limit.
        max: usize,
    },
    /// A face names a vertex that does not exist.
    #[error("triangle {tri} names vertex {index}, but there are {count} vertices")]
    BadIndex {
        /// The triangle.
        tri: usize,
        /// The index it names (0-based).
        index: u32,
        /// Vertices in the mesh.
        count: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} has a coordinate that is not a finite number ({value})")]
    NotFinite {
        /// The vertex.
        vertex: usize,
        /// The coordinate.
        value: f32,
    },
    /// A triangle with a repeated vertex or no area.
    #[error("triangle {tri} ({a}, {b}, {c}) is degenerate: {why}")]
    Degenerate {
        /// The triangle.
        tri: usize,
        /// Its vertices.
        a: u32,
        /// Its vertices.
        b: u32,
        /// Its vertices.
        c: u32,
        /// A repeated vertex or zero area.
        why: &'static str,
    },
    /// The same three vertices twice.
    #[error("triangles {first} and {second} have the same three vertices")]
    Duplicate {
        /// The first.
        first: usize,
        /// The repeat.
        second: usize,
    },
    /// A vertex in no triangle.
    #[error("vertex {0} is in no triangle (a particle with no springs would fall alone)")]
    Unreferenced(usize),
    /// An edge in more than two triangles.
    #[error("edge ({a}, {b}) is in {count} triangles: a cloth must be a manifold (each edge in one or two)")]
    NonManifold {
        /// One end.
        a: u32,
        /// The other.
        b: u32,
        /// Triangles sharing it.
        count: usize,
    },
    /// Two triangles on an edge wound the same way: their normals disagree.
    #[error(
        "triangles {t0} and {t1} both run edge ({a}, {b}) the same way: their windings disagree (normals flip between them)"
    )]
    Winding {
        /// One end.
        a: u32,
        /// The other.
        b: u32,
        /// A triangle.
        t0: usize,
        /// The other.
        t1: usize,
    },
    /// A pinned vertex (in the file's numbering) that is in no triangle: dropped.
    #[error(
        "pinned vertex {0} is in no triangle: such vertices are dropped (a particle with no springs would fall alone)"
    )]
    DroppedPin(u32),
    /// A pinned vertex that does not exist.
    #[error("pinned vertex {vertex} does not exist: the mesh has {count} vertices (0 ..= {})", count.saturating_sub(1))]
    NoSuchPin {
        /// The vertex listed.
        vertex: u32,
        /// Vertices in the mesh.
        count: usize,
    },
    /// A vertex farther from the origin than positions in f32 can be simulated.
    #[error(
        "vertex {vertex} lies at {value:e} m, beyond the ±{max} m a cloth is simulated in (f32 positions: squared lengths overflow, and springs shorter than the positions resolve): scale the mesh down or move it nearer the origin"
    )]
    TooFar {
        /// The vertex.
        vertex: usize,
        /// Its coordinate farthest from the origin, m.
        value: f32,
        /// The limit, m ([`MAX_COORDINATE`]).
        max: f32,
    },
    /// An edge too short for the positions' resolution where the mesh lies.
    #[error(
        "edge ({a}, {b}) is {len:.3e} m long, but f32 positions {far} m from the origin are {ulp:.1e} m apart: a spring needs at least {need:.1e} m ({SPRING_ULPS} times that) to have a length: scale the mesh up or move it nearer the origin"
    )]
    TooShort {
        /// One end.
        a: u32,
        /// The other.
        b: u32,
        /// Its length, m.
        len: f32,
        /// The largest coordinate of the mesh, m.
        far: f32,
        /// The spacing of f32 values there, m.
        ulp: f32,
        /// The shortest edge allowed, m.
        need: f32,
    },
    /// More springs than [`MAX_SPRINGS_PER_VERTEX`] per vertex (XPBD keeps each spring's
    /// λ in the particles' scratch buffers): a mesh of many handles, not a cloth.
    #[error(
        "the mesh has {springs} springs for {vertices} vertices; the solvers hold at most {} per vertex (a cloth of one sheet has at most 6)",
        MAX_SPRINGS_PER_VERTEX
    )]
    TooManySprings {
        /// Its springs (edges and bending springs).
        springs: usize,
        /// Its vertices.
        vertices: usize,
    },
}

impl TriMesh {
    /// Refuses a mesh a cloth cannot be (see the module's text), with the first problem.
    pub fn check(&self) -> Result<(), MeshError> {
        let count = self.positions.len();
        if self.triangles.is_empty() {
            return Err(MeshError::Empty);
        }
        if count > MAX_MESH_VERTICES {
            return Err(MeshError::TooManyVertices { count, max: MAX_MESH_VERTICES });
        }
        for (vertex, p) in self.positions.iter().enumerate() {
            if let Some(&value) = p.iter().find(|c| !c.is_finite()) {
                return Err(MeshError::NotFinite { vertex, value });
            }
            if let Some(&value) = p.iter().find(|c| c.abs() > MAX_COORDINATE) {
                return Err(MeshError::TooFar { vertex, value, max: MAX_COORDINATE });
            }
        }
        // The spacing of f32 values at the largest coordinate (its ulp), and the shortest
        // edge that resolves to a length there.
        let far = self.positions.iter().flatten().fold(0.0f32, |m, c| m.max(c.abs()));
        let ulp = f32::from_bits(far.max(f32::MIN_POSITIVE).to_bits() + 1) - far.max(f32::MIN_POSITIVE);
        let need = SPRING_ULPS * ulp;
        for tri in &self.triangles {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let (Some(pa), Some(pb)) = (self.positions.get(a as usize), self.positions.get(b as usize)) else {
                    continue; // BadIndex, below
                };
                let len = glam::Vec3::from(*pa).distance(glam::Vec3::from(*pb));
                if len > 0.0 && len < need {
                    return Err(MeshError::TooShort { a, b, len, far, ulp, need });
                }
            }
        }
        if let Some(uv) = &self.uvs {
            for (vertex, t) in uv.iter().enumerate() {
                if let Some(&value) = t.iter().find(|c| !c.is_finite()) {
                    return Err(MeshError::NotFinite { vertex, value });
                }
            }
        }
        let mut seen: HashMap<[u32; 3], usize> = HashMap::with_capacity(self.triangles.len());
        let mut used = vec![false; count];
        for (tri, &[a, b, c]) in self.triangles.iter().enumerate() {
            for index in [a, b, c] {
                if index as usize >= count {
                    return Err(MeshError::BadIndex { tri, index, count });
                }
                used[index as usize] = true;
            }
            if a == b || b == c || a == c {
                return Err(MeshError::Degenerate { tri, a, b, c, why: "a vertex repeated" });
            }
            if self.area2(tri) <= 0.0 {
                return Err(MeshError::Degenerate { tri, a, b, c, why: "no area (its corners are on a line)" });
            }
            let mut key = [a, b, c];
            key.sort_unstable();
            if let Some(&first) = seen.get(&key) {
                return Err(MeshError::Duplicate { first, second: tri });
            }
            seen.insert(key, tri);
        }
        if let Some(v) = used.iter().position(|u| !u) {
            return Err(MeshError::Unreferenced(v));
        }
        // Every directed edge once; an undirected edge in at most two triangles.
        let mut directed: HashMap<(u32, u32), usize> = HashMap::with_capacity(3 * self.triangles.len());
        let mut undirected: HashMap<(u32, u32), usize> = HashMap::with_capacity(3 * self.triangles.len());
        for (tri, t) in self.triangles.iter().enumerate() {
            for e in 0..3 {
                let (a, b) = (t[e], t[(e + 1) % 3]);
                let n = undirected.entry((a.min(b), a.max(b))).or_insert(0);
                *n += 1;
                if *n > 2 {
                    return Err(MeshError::NonManifold { a: a.min(b), b: a.max(b), count: *n });
                }
                if let Some(&t0) = directed.get(&(a, b)) {
                    return Err(MeshError::Winding { a, b, t0, t1: tri });
                }
                directed.insert((a, b), tri);
            }
        }
        MeshSprings::build(self).map(|_| ())
    }

    /// Twice the area of triangle `t`, m².
    pub fn area2(&self, t: usize) -> f32 {
        let [a, b, c] = self.triangles[t].map(|i| glam::Vec3::from(self.positions[i as usize]));
        (b - a).cross(c - a).length()
    }

    /// Each vertex's share of the cloth's area: a third of each of its triangles', m².
    pub fn vertex_areas(&self) -> Vec<f32> {
        let mut area = vec![0.0f32; self.positions.len()];
        for (t, tri) in self.triangles.iter().enumerate() {
            let third = self.area2(t) / 6.0;
            for &v in tri {
                area[v as usize] += third;
            }
        }
        area
    }

    /// The cloth's area, m².
    pub fn area(&self) -> f32 {
        (0..self.triangles.len()).map(|t| self.area2(t)).sum::<f32>() / 2.0
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;

    const SQUARE: &str = "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nf 1 4 3 2\n";

    #[test]
    fn the_file_order_of_vertices_is_kept_and_polygons_become_fans() {
        let m = parse_obj("# a quad\nv 0 0 0\nv 1 0 0 # x\nv 1 0 1\nv 0 0 1\nvn 0 1 0\ng a\nf 1//1 4//1 3//1 2//1\n")
            .unwrap();
        assert_eq!(m.positions[1], [1.0, 0.0, 0.0]);
        assert_eq!(m.triangles, vec![[0, 3, 2], [0, 2, 1]]);
        assert_eq!(m.uvs, None);
        m.check().unwrap();
        // Negative indices count back from the last vertex read.
        let m = parse_obj("v 0 0 0\nv 1 0 0\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\nf -3/-3 -1/-1 -2/-2\n").unwrap();
        assert_eq!(m.triangles, vec![[0, 2, 1]]);
        assert_eq!(m.uvs, Some(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]));
    }

    #[test]
    fn a_grid_mesh_round_trips_through_obj_and_has_the_grids_springs() {
        let m = grid_mesh(5, 2.0);
        assert_eq!(parse_obj(&to_obj(&m)).unwrap(), m);
        m.check().unwrap();
        let s = MeshSprings::build(&m).unwrap();
        // 5×5: 40 structural + 16 diagonals = 56 edges; interior edges 56 − 16 = 40, each
        // with one bending spring (none repeats, none is an edge).
        assert_eq!(s.edges.len(), 56);
        assert_eq!(s.bends.len(), 40);
        // An interior vertex: 6 edges and 6 bending springs, edges first.
        assert_eq!(s.slots[12].len(), 12);
        assert!(s.slots[12][..6].iter().all(|&k| s.is_edge(k)) && s.slots[12][6..].iter().all(|&k| !s.is_edge(k)));
        // Areas: 4 m² in all; an interior vertex holds a sixth of a 0.5 m quad's six triangles.
        assert!((m.area() - 4.0).abs() < 1e-5, "{}", m.area());
        let a = m.vertex_areas();
        assert!((a.iter().sum::<f32>() - 4.0).abs() < 1e-5);
        assert!((a[12] - 0.25).abs() < 1e-6, "{}", a[12]);
    }

    #[test]
    fn every_bad_mesh_is_refused_in_one_line() {
        let cases: Vec<(String, &str)> = vec![
            ("v 0 0 0\n".into(), "no triangles"),
            ("v 0 0 0\nv 1 0 0\nv nan 0 1\nf 1 2 3\n".into(), "vertex 2 has a coordinate that is not a finite"),
            ("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n".into(), "triangle 0 (0, 1, 2) is degenerate: no area"),
            ("v 0 0 0\nv 1 0 0\nv 2 0 1\nf 1 2 2\n".into(), "degenerate: a vertex repeated"),
            (format!("{SQUARE}f 1 3 2\n"), "triangles 1 and 2 have the same three vertices"),
            (format!("{SQUARE}v 5 5 5\n"), "vertex 4 is in no triangle"),
            (
                "v 0 0 0\nv 1 0 0\nv 0 0 1\nv 0 1 0\nv 0 -1 0\nf 1 2 3\nf 2 1 4\nf 1 2 5\n".into(),
                "edge (0, 1) is in 3 triangles",
            ),
            ("v 0 0 0\nv 1 0 0\nv 0 0 1\nv 1 0 1\nf 1 2 3\nf 1 2 4\n".into(), "both run edge (0, 1) the same way"),
            ("v 0 0 0\nf 1 2 3\n".into(), "line 2: vertex index 2 in `2`: there are 1 so far"),
            ("v 0 0\n".into(), "line 1: a `v` line needs 3 numbers, it has 2"),
            ("v 0 zero 0\n".into(), "line 1: `zero` is not a number"),
            ("v 0 0 0\nv 1 0 0\nf 1 2\n".into(), "line 3: a face needs 3 corners, it has 2"),
            // A dart (A, B, C reflex, D) fanned from B: its first triangle folds over the
            // second. (From its tip A the same dart fans well: below.)
            (
                "v 0 0 0\nv 1 0 1\nv 0 0 0.3\nv -1 0 1\nf 2 3 4 1\n".into(),
                "line 5: a face of 4 corners is not convex enough to fan from its first corner: its triangle 0",
            ),
            // What f32 cannot simulate: a square scaled to 1e20 m (its squared lengths
            // overflow), and a 0.1 mm triangle 1 km from the origin (positions there are
            // 6.1e-5 m apart: its springs would be a couple of steps of rounding long).
            ("v 0 0 0\nv 1e20 0 0\nv 1e20 0 1e20\nf 1 2 3\n".into(), "vertex 1 lies at 1e20 m, beyond the ±10000 m"),
            (
                "v 1000 0 0\nv 1000.0001 0 0\nv 1000 0 0.0001\nf 1 2 3\n".into(),
                "is 1.221e-4 m long, but f32 positions 1000.0001 m from the origin are 6.1e-5 m apart",
            ),
        ];
        for (text, want) in cases {
            let e = match parse_obj(&text) {
                Err(e) => e,
                Ok(m) => m.check().expect_err(&text),
            };
            let line = e.to_string();
            assert!(line.contains(want), "{text:?}: {line}");
            assert!(!line.contains('\n'), "{line}");
        }
    }

    #[test]
    fn obj_files_as_modelling_tools_write_them_are_read() {
        // CRLF line ends, objects, groups, smoothing groups, materials, normals, parameter
        // space vertices, negative (relative) indices, a pentagon and a dart fanned from its
        // convex tip, and a stray vertex (Blender leaves them; an n-gon fill's centre).
        let text = "mtllib cloth.mtl\r\no Cloth\r\nv 0 0 0\r\nv 1 0 0\r\nv 1.5 0 0.8\r\nv 0.5 0 1.4\r\n\
                    v -0.5 0 0.8\r\nv 9 9 9\r\nvn 0 1 0\r\nvp 0.5\r\ng skirt\r\nusemtl linen\r\ns 1\r\n\
                    f -6//1 -5//1 -4//1 -3//1 -2//1\r\nv 0 0 -1\r\nv 1 0 -1\r\nv 0.5 0 -0.7\r\n\
                    f 7 8 9 2 1\r\n";
        let m = parse_obj(text).unwrap();
        assert_eq!(m.positions.len(), 9);
        // The pentagon's fan (3 triangles) from vertex 0, then the second face's (3).
        assert_eq!(m.triangles[..3], [[0, 1, 2], [0, 2, 3], [0, 3, 4]]);
        assert_eq!(m.triangles.len(), 6);
        // Placed, the stray vertex (file index 5) is dropped and the rest keep their order;
        // pins name the file's vertices.
        let placed = PlacedMesh::new(&m, &Placement::default()).unwrap();
        assert_eq!(placed.dropped(), 1);
        assert_eq!(placed.mesh.positions.len(), 8);
        assert_eq!(placed.file_of, [0, 1, 2, 3, 4, 6, 7, 8]);
        assert_eq!(placed.mesh.positions[5], [0.0, 0.0, -1.0], "file vertex 6 is mesh vertex 5");
        let held = placed.pinned(&MeshPinning::Vertices(vec![6, 8])).unwrap();
        assert_eq!(held.iter().filter(|h| **h).count(), 2);
        assert!(held[5] && held[7]);
        let e = placed.pinned(&MeshPinning::Vertices(vec![5])).unwrap_err().to_string();
        assert!(e.starts_with("pinned vertex 5 is in no triangle"), "{e}");
        let e = placed.pinned(&MeshPinning::Vertices(vec![9])).unwrap_err().to_string();
        assert_eq!(e, "pinned vertex 9 does not exist: the mesh has 9 vertices (0 ..= 8)");
        // The dart of the refusals above, fanned from its tip: two triangles, one winding.
        let dart = parse_obj("v 0 0 0\nv 1 0 1\nv 0 0 0.3\nv -1 0 1\nf 1 2 3 4\n").unwrap();
        assert_eq!(dart.triangles, [[0, 1, 2], [0, 2, 3]]);
        dart.check().unwrap();
    }

    #[test]
    fn placement_pinning_masses_and_tethers() {
        // The 3×3 grid mesh of 2 m: x in [-1, 1], z in [0, 2], y = 0.
        let m = grid_mesh(3, 2.0);
        // Rotated −90° about x (right-handed: +z turns to +y), the sheet stands up: z = 2
        // goes to y = 2 after the scale of 0.5 and a lift of 1 m.
        let p = Placement { scale: [0.5; 3], rotate_deg: [-90.0, 0.0, 0.0], translate: [0.0, 1.0, 0.0] };
        let placed = m.placed(&p);
        let far = placed.positions[8]; // (1, 0, 2) → (0.5, 0, 1) → (0.5, 1, 0) + (0, 1, 0)
        for (got, want) in far.iter().zip([0.5, 2.0, 0.0]) {
            assert!((got - want).abs() < 1e-6, "{far:?}");
        }
        // Rotation keeps the windings: the first triangle's normal is the rotated normal.
        let [a, b, c] = placed.triangles[0].map(|i| glam::Vec3::from(placed.positions[i as usize]));
        let nrm = (b - a).cross(c - a).normalize();
        let [a0, b0, c0] = m.triangles[0].map(|i| glam::Vec3::from(m.positions[i as usize]));
        let n0 = (b0 - a0).cross(c0 - a0).normalize();
        assert!((p.matrix().transform_vector3(n0).normalize() - nrm).length() < 1e-6);
        // A mirror flips the windings back: the normal is the mirrored one, not its reverse.
        let mirror = Placement { scale: [-1.0, 1.0, 1.0], ..Placement::default() };
        let mm = m.placed(&mirror);
        let [a, b, c] = mm.triangles[0].map(|i| glam::Vec3::from(mm.positions[i as usize]));
        assert!(((b - a).cross(c - a).normalize() - n0).length() < 1e-6);
        // Pinning by rule and by list, after placement: the top row (y = 2) above 1.9 m.
        let held = placed.pinned(&MeshPinning::AboveY(1.9)).unwrap();
        assert_eq!(held.iter().filter(|h| **h).count(), 3);
        assert!(held[6] && held[7] && held[8]);
        assert_eq!(placed.pinned(&MeshPinning::BelowY(0.5)).unwrap(), vec![false; 9]);
        let e = placed.pinned(&MeshPinning::Vertices(vec![0, 9])).unwrap_err().to_string();
        assert_eq!(e, "pinned vertex 9 does not exist: the mesh has 9 vertices (0 ..= 8)");
        // Masses follow the areas: 1 kg over 4 m² (unplaced); the centre vertex has six
        // triangles of 0.5 m² each → 1 m² / 4 m² = 0.25 kg, a corner with one 0.5 m²
        // triangle 1/24 kg, and the masses sum to the total.
        let mass = m.vertex_masses(1.0);
        assert!((mass.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        assert!((mass[4] - 0.25).abs() < 1e-6, "{}", mass[4]);
        assert!((mass[2] - 1.0 / 24.0).abs() < 1e-6, "{}", mass[2]);
        // Tethers: the two nearest pins, nearest first, with their distances; none on pins.
        let t = placed.tethers(&held, None);
        assert!(t[7].is_empty());
        assert_eq!(t[1].iter().map(|x| x.0).collect::<Vec<_>>(), vec![7, 6]);
        assert!((t[1][0].1 - 1.0).abs() < 1e-6 && (t[1][1].1 - 0.5f32.hypot(1.0)).abs() < 1e-6, "{:?}", t[1]);
    }

    #[test]
    fn a_file_too_big_or_missing_is_refused_naming_it() {
        let e = load_obj(Path::new("/nonexistent/skirt.obj")).unwrap_err().to_string();
        assert!(e.starts_with("/nonexistent/skirt.obj: cannot read it"), "{e}");
        // A sparse file one byte over the limit: refused by its size, before it is read.
        let path = std::env::temp_dir().join(format!("clothlab-big-{}.obj", std::process::id()));
        std::fs::File::create(&path).unwrap().set_len(MAX_MESH_BYTES + 1).unwrap();
        let e = load_obj(&path).unwrap_err();
        std::fs::remove_file(&path).unwrap();
        assert_eq!(e.error, MeshError::TooBig { size: MAX_MESH_BYTES + 1, max: MAX_MESH_BYTES });
    }
}
