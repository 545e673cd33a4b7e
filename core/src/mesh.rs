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

use std::collections::HashMap;
use std::path::Path;

use thiserror::Error;

use crate::tables::TETHER_SLOTS;

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

/// A mesh file's error with the file's name: `skirt.obj: line 3: …`.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("{path}: {error}")]
pub struct MeshFileError {
    /// The file as given.
    pub path: String,
    /// What is wrong.
    pub error: MeshError,
}

/// Reads and checks the mesh file at `path` by its extension: OBJ ([`load_obj`]) or glTF
/// (`.glb`, `.gltf`: [`load_gltf`], the mesh named `name` if given).
pub fn load_mesh(path: &Path, name: Option<&str>) -> Result<TriMesh, MeshFileError> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let err = |error| MeshFileError { path: path.display().to_string(), error };
    match ext.as_deref() {
        Some("glb" | "gltf") => load_gltf(path, name),
        Some("obj") if name.is_some() => {
            Err(err(MeshError::Read("`mesh_name` picks a mesh of a glTF file; an OBJ file holds one".into())))
        }
        Some("obj") => load_obj(path),
        _ => Err(err(MeshError::Read("not a mesh file clothlab reads: give an .obj, .glb or .gltf file".into()))),
    }
}

/// Reads and checks the first triangle primitive of the glTF file at `path` (`.glb`, or
/// `.gltf` with its buffers beside it) — of the mesh named `name`, if given — with the
/// gltf crate: positions, the first texture coordinates if it has them, and triangles, in
/// the mesh's own space (a scene places it; node transforms are not applied). What
/// `sim --record` writes reads back as its first frame.
pub fn load_gltf(path: &Path, name: Option<&str>) -> Result<TriMesh, MeshFileError> {
    let err = |error| MeshFileError { path: path.display().to_string(), error };
    let size = std::fs::metadata(path).map_err(|e| err(MeshError::Read(e.to_string())))?.len();
    if size > MAX_MESH_BYTES {
        return Err(err(MeshError::TooBig { size, max: MAX_MESH_BYTES }));
    }
    let (doc, buffers, _) =
        gltf::import(path).map_err(|e| err(MeshError::Read(format!("not a glTF file clothlab can read: {e}"))))?;
    fn triangles<'a>(m: &gltf::Mesh<'a>) -> Option<gltf::Primitive<'a>> {
        m.primitives().find(|p| p.mode() == gltf::mesh::Mode::Triangles)
    }
    let chosen = match name {
        Some(want) => {
            let Some(m) = doc.meshes().find(|m| m.name() == Some(want)) else {
                let names: Vec<String> =
                    doc.meshes().map(|m| format!("`{}`", m.name().unwrap_or("(unnamed)"))).collect();
                return Err(err(MeshError::Read(format!("no mesh named `{want}` (it has {})", names.join(", ")))));
            };
            triangles(&m).ok_or_else(|| err(MeshError::Read(format!("mesh `{want}` has no triangle primitive"))))?
        }
        None => doc.meshes().find_map(|m| triangles(&m)).ok_or_else(|| err(MeshError::Empty))?,
    };
    let reader = chosen.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let positions: Vec<[f32; 3]> = reader
        .read_positions()
        .ok_or_else(|| err(MeshError::Read("its triangle primitive has no positions".into())))?
        .collect();
    if positions.len() > MAX_MESH_VERTICES {
        return Err(err(MeshError::TooManyVertices { count: positions.len(), max: MAX_MESH_VERTICES }));
    }
    let indices: Vec<u32> = match reader.read_indices() {
        Some(i) => i.into_u32().collect(),
        None => (0..positions.len() as u32).collect(),
    };
    if !indices.len().is_multiple_of(3) {
        return Err(err(MeshError::Read(format!("{} indices: not whole triangles", indices.len()))));
    }
    let triangles = indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
    let uvs = reader
        .read_tex_coords(0)
        .map(|t| t.into_f32().collect::<Vec<[f32; 2]>>())
        .filter(|uv| uv.len() == positions.len());
    let mesh = TriMesh { positions, uvs, triangles };
    mesh.without_unreferenced().0.check().map_err(err)?;
    Ok(mesh)
}

/// Reads and checks the OBJ file at `path`.
pub fn load_obj(path: &Path) -> Result<TriMesh, MeshFileError> {
    let err = |error| MeshFileError { path: path.display().to_string(), error };
    let size = std::fs::metadata(path).map_err(|e| err(MeshError::Read(e.to_string())))?.len();
    if size > MAX_MESH_BYTES {
        return Err(err(MeshError::TooBig { size, max: MAX_MESH_BYTES }));
    }
    let text = std::fs::read_to_string(path).map_err(|e| err(MeshError::Read(e.to_string())))?;
    let mesh = parse_obj(&text).map_err(err)?;
    // Checked as the cloth it makes: without its vertices in no triangle, which
    // `PlacedMesh` drops (the mesh returned keeps the file's numbering, for pins).
    mesh.without_unreferenced().0.check().map_err(err)?;
    Ok(mesh)
}

/// Parses OBJ text (not checked: see [`TriMesh::check`]).
pub fn parse_obj(text: &str) -> Result<TriMesh, MeshError> {
    let mut positions: Vec<[f32; 3]> = Vec::new();
    let mut texcoords: Vec<[f32; 2]> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    // Per triangle corner, its texture coordinate index, when every corner has one.
    let mut corner_uv: Vec<Option<usize>> = Vec::new();
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let syntax = |what: String| MeshError::Syntax { line, what };
        let content = raw.split('#').next().unwrap_or("").trim();
        let mut words = content.split_whitespace();
        let Some(tag) = words.next() else { continue };
        let numbers = |words: std::str::SplitWhitespace<'_>, want: usize, what: &str| -> Result<Vec<f32>, MeshError> {
            let v: Vec<f32> = words
                .map(|w| w.parse::<f32>().map_err(|_| syntax(format!("`{w}` is not a number in a `{what}` line"))))
                .collect::<Result<_, _>>()?;
            if v.len() < want {
                return Err(syntax(format!("a `{what}` line needs {want} numbers, it has {}", v.len())));
            }
            Ok(v)
        };
        match tag {
            "v" => {
                let v = numbers(words, 3, "v")?;
                positions.push([v[0], v[1], v[2]]);
                if positions.len() > MAX_MESH_VERTICES {
                    return Err(MeshError::TooManyVertices { count: positions.len(), max: MAX_MESH_VERTICES });
                }
            }
            "vt" => {
                let v = numbers(words, 2, "vt")?;
                texcoords.push([v[0], v[1]]);
            }
            "f" => {
                let mut corners: Vec<(u32, Option<usize>)> = Vec::new();
                for w in words {
                    let mut parts = w.split('/');
                    let resolve = |s: &str, count: usize, what: &str| -> Result<usize, MeshError> {
                        let i: i64 = s.parse().map_err(|_| syntax(format!("`{w}` is not a face corner")))?;
                        let idx = if i > 0 { i - 1 } else { count as i64 + i };
                        if i == 0 || idx < 0 || idx >= count as i64 {
                            return Err(syntax(format!("{what} index {i} in `{w}`: there are {count} so far")));
                        }
                        Ok(idx as usize)
                    };
                    let v = resolve(parts.next().unwrap_or(""), positions.len(), "vertex")?;
                    let vt = match parts.next() {
                        Some(s) if !s.is_empty() => Some(resolve(s, texcoords.len(), "texture coordinate")?),
                        _ => None,
                    };
                    corners.push((v as u32, vt));
                }
                if corners.len() < 3 {
                    return Err(syntax(format!("a face needs 3 corners, it has {}", corners.len())));
                }
                if let Some(c) = fan_fold(&positions, &corners.iter().map(|c| c.0).collect::<Vec<_>>()) {
                    return Err(syntax(format!(
                        "a face of {} corners is not convex enough to fan from its first corner: its triangle {c} (corners 1, {}, {}) would fold over the others; split it into triangles or convex polygons",
                        corners.len(),
                        c + 2,
                        c + 3
                    )));
                }
                for c in 1..corners.len() - 1 {
                    let tri = [corners[0], corners[c], corners[c + 1]];
                    triangles.push(tri.map(|t| t.0));
                    corner_uv.extend(tri.map(|t| t.1));
                }
            }
            _ => {}
        }
    }
    let uvs = if !triangles.is_empty() && corner_uv.iter().all(Option::is_some) {
        let mut uv: Vec<Option<[f32; 2]>> = vec![None; positions.len()];
        for (t, c) in triangles.iter().flatten().zip(&corner_uv) {
            let slot = &mut uv[*t as usize];
            if slot.is_none() {
                *slot = c.map(|i| texcoords[i]);
            }
        }
        // Unreferenced vertices are refused by `check`; until then they get (0, 0).
        Some(uv.into_iter().map(|u| u.unwrap_or([0.0, 0.0])).collect())
    } else {
        None
    };
    Ok(TriMesh { positions, uvs, triangles })
}

/// The first triangle of the fan from corner 0 of the polygon `corners` (indices into
/// `positions`) that faces against the polygon's normal (Newell's, which holds for
/// non-planar polygons too), if any: such a fan folds over itself. A triangle or a convex
/// polygon, planar or not, has none.
fn fan_fold(positions: &[[f32; 3]], corners: &[u32]) -> Option<usize> {
    if corners.len() <= 3 {
        return None;
    }
    let p = |k: usize| glam::Vec3::from(positions[corners[k] as usize]);
    let mut normal = glam::Vec3::ZERO;
    for k in 0..corners.len() {
        let (a, b) = (p(k), p((k + 1) % corners.len()));
        normal += glam::Vec3::new((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y));
    }
    (1..corners.len() - 1).find(|&c| (p(c) - p(0)).cross(p(c + 1) - p(0)).dot(normal) < 0.0).map(|c| c - 1)
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

/// Where a mesh goes in the scene: scaled about the origin, rotated (about x, then y, then
/// z), then moved.
#[derive(Debug, Clone, PartialEq)]
pub struct Placement {
    /// Scale per axis. Default 1.
    pub scale: [f32; 3],
    /// Rotation about x, y and z, degrees, applied in that order. Default 0.
    pub rotate_deg: [f32; 3],
    /// Translation, m. Default 0.
    pub translate: [f32; 3],
}

impl Default for Placement {
    fn default() -> Self {
        Self { scale: [1.0; 3], rotate_deg: [0.0; 3], translate: [0.0; 3] }
    }
}

impl Placement {
    /// The placement as one affine transform.
    pub fn matrix(&self) -> glam::Affine3A {
        let [rx, ry, rz] = self.rotate_deg.map(f32::to_radians);
        let rot = glam::Quat::from_euler(glam::EulerRot::ZYX, rz, ry, rx);
        glam::Affine3A::from_scale_rotation_translation(self.scale.into(), rot, self.translate.into())
    }
}

/// Which vertices of a mesh are held (after placement).
#[derive(Debug, Clone, PartialEq, Default)]
pub enum MeshPinning {
    /// None: the cloth falls freely.
    #[default]
    None,
    /// These vertices (0-based, in the file's order).
    Vertices(Vec<u32>),
    /// Every vertex with y below this height, m (placed).
    BelowY(f32),
    /// Every vertex with y above this height, m (placed): a skirt's waist.
    AboveY(f32),
}

impl TriMesh {
    /// The mesh moved by `placement` (triangles and uvs unchanged; a mirroring scale,
    /// an odd number of negative factors, flips the windings back so normals keep their
    /// side).
    pub fn placed(&self, placement: &Placement) -> TriMesh {
        let m = placement.matrix();
        let positions = self.positions.iter().map(|&p| m.transform_point3(p.into()).into()).collect();
        let mirrored = placement.scale.iter().filter(|s| **s < 0.0).count() % 2 == 1;
        let triangles =
            if mirrored { self.triangles.iter().map(|&[a, b, c]| [a, c, b]).collect() } else { self.triangles.clone() };
        TriMesh { positions, uvs: self.uvs.clone(), triangles }
    }

    /// The mesh without its vertices in no triangle (a modelling tool's stray points, the
    /// centre an n-gon fill leaves), and per vertex kept its index here (the file's
    /// numbering). A mesh whose triangles name a vertex that does not exist is returned
    /// whole, for [`TriMesh::check`] to refuse.
    pub fn without_unreferenced(&self) -> (TriMesh, Vec<u32>) {
        let count = self.positions.len();
        let identity = || (self.clone(), (0..count as u32).collect());
        let mut used = vec![false; count];
        for &v in self.triangles.iter().flatten() {
            match used.get_mut(v as usize) {
                Some(u) => *u = true,
                None => return identity(),
            }
        }
        if used.iter().all(|u| *u) {
            return identity();
        }
        let file_of: Vec<u32> = (0..count as u32).filter(|&v| used[v as usize]).collect();
        let mut new_of = vec![0u32; count];
        for (k, &v) in file_of.iter().enumerate() {
            new_of[v as usize] = k as u32;
        }
        let mesh = TriMesh {
            positions: file_of.iter().map(|&v| self.positions[v as usize]).collect(),
            uvs: self.uvs.as_ref().map(|uv| file_of.iter().map(|&v| uv[v as usize]).collect()),
            triangles: self.triangles.iter().map(|t| t.map(|v| new_of[v as usize])).collect(),
        };
        (mesh, file_of)
    }

    /// Per vertex, whether `pinning` holds it; a listed vertex that does not exist is
    /// refused.
    pub fn pinned(&self, pinning: &MeshPinning) -> Result<Vec<bool>, MeshError> {
        let count = self.positions.len();
        let mut held = vec![false; count];
        match pinning {
            MeshPinning::None => {}
            MeshPinning::Vertices(list) => {
                for &v in list {
                    *held.get_mut(v as usize).ok_or(MeshError::NoSuchPin { vertex: v, count })? = true;
                }
            }
            MeshPinning::BelowY(y) => held.iter_mut().zip(&self.positions).for_each(|(h, p)| *h = p[1] < *y),
            MeshPinning::AboveY(y) => held.iter_mut().zip(&self.positions).for_each(|(h, p)| *h = p[1] > *y),
        }
        Ok(held)
    }

    /// Each vertex's mass for a cloth of `total` kg: its share of the area
    /// ([`TriMesh::vertex_areas`]), so a uniform fabric has the same density everywhere.
    pub fn vertex_masses(&self, total: f32) -> Vec<f32> {
        let areas = self.vertex_areas();
        let sum: f32 = areas.iter().sum();
        areas.iter().map(|a| total * a / sum).collect()
    }

    /// Per vertex, tethers to the (up to) two nearest held vertices, as (pin, rest
    /// distance): what `grid::build_grid` gives a grid pinned by a list of points. Held vertices
    /// get none. Brute force over the pins, so a mesh with more than 2.5e8 vertex–pin pairs
    /// gets none (as the grid).
    /// With `part_of` (each vertex's cloth, in a scene of several), only to pins of the
    /// vertex's own cloth.
    pub fn tethers(&self, held: &[bool], part_of: Option<&[u32]>) -> Vec<Vec<(u32, f32)>> {
        let pins: Vec<u32> = (0..held.len() as u32).filter(|&v| held[v as usize]).collect();
        let same = |a: usize, b: u32| part_of.is_none_or(|p| p[a] == p[b as usize]);
        let dist = |a: usize, b: usize| glam::Vec3::from(self.positions[a]).distance(self.positions[b].into());
        if pins.len() * held.len() > 250_000_000 {
            return vec![Vec::new(); held.len()];
        }
        (0..held.len())
            .map(|v| {
                if held[v] {
                    return Vec::new();
                }
                let mut near: Vec<(f32, u32)> =
                    pins.iter().filter(|&&p| same(v, p)).map(|&p| (dist(v, p as usize), p)).collect();
                near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                near.into_iter().take(TETHER_SLOTS).map(|(d, p)| (p, d)).collect()
            })
            .collect()
    }
}

/// The springs a mesh gives, with each vertex's slots.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshSprings {
    /// Structural springs: every edge once, `(a, b)` with `a < b`.
    pub edges: Vec<[u32; 2]>,
    /// Bending springs: across every interior edge, between the two vertices opposite it,
    /// `(a, b)` with `a < b`, each pair once and none that is also an edge.
    pub bends: Vec<[u32; 2]>,
    /// Per vertex, its springs in slot order: indices into `edges` then into `bends`
    /// (as `edges.len() + k`); edges first, as many as the vertex has.
    pub slots: Vec<Vec<u32>>,
}

impl MeshSprings {
    /// The springs of `mesh` (whose indices are in range), of any valence; refused only
    /// past [`MAX_SPRINGS_PER_VERTEX`] springs per vertex in all.
    pub fn build(mesh: &TriMesh) -> Result<Self, MeshError> {
        let count = mesh.positions.len();
        // Each undirected edge with the vertices opposite it (one or two).
        let mut opposite: HashMap<(u32, u32), Vec<u32>> = HashMap::with_capacity(3 * mesh.triangles.len());
        for t in &mesh.triangles {
            for e in 0..3 {
                let (a, b, o) = (t[e], t[(e + 1) % 3], t[(e + 2) % 3]);
                opposite.entry((a.min(b), a.max(b))).or_default().push(o);
            }
        }
        let mut edges: Vec<[u32; 2]> = opposite.keys().map(|&(a, b)| [a, b]).collect();
        edges.sort_unstable();
        let edge_set: std::collections::HashSet<[u32; 2]> = edges.iter().copied().collect();
        let mut bends: Vec<[u32; 2]> = opposite
            .values()
            .filter(|o| o.len() == 2 && o[0] != o[1])
            .map(|o| [o[0].min(o[1]), o[0].max(o[1])])
            .filter(|b| !edge_set.contains(b))
            .collect();
        bends.sort_unstable();
        bends.dedup();
        let mut slots: Vec<Vec<u32>> = vec![Vec::new(); count];
        for (k, &[a, b]) in edges.iter().enumerate() {
            slots[a as usize].push(k as u32);
            slots[b as usize].push(k as u32);
        }
        let base = edges.len() as u32;
        for (k, &[a, b]) in bends.iter().enumerate() {
            slots[a as usize].push(base + k as u32);
            slots[b as usize].push(base + k as u32);
        }
        let springs = edges.len() + bends.len();
        if springs > MAX_SPRINGS_PER_VERTEX * count {
            return Err(MeshError::TooManySprings { springs, vertices: count });
        }
        Ok(Self { edges, bends, slots })
    }

    /// The other end of spring `k` (as in `slots`) seen from vertex `v`.
    pub fn other(&self, k: u32, v: u32) -> u32 {
        let [a, b] = self.spring(k);
        if a == v { b } else { a }
    }

    /// Spring `k` (as in `slots`): an edge or a bending spring.
    pub fn spring(&self, k: u32) -> [u32; 2] {
        let k = k as usize;
        if k < self.edges.len() { self.edges[k] } else { self.bends[k - self.edges.len()] }
    }

    /// Whether spring `k` (as in `slots`) is an edge.
    pub fn is_edge(&self, k: u32) -> bool {
        (k as usize) < self.edges.len()
    }
}

/// An `n × n` grid of `size` m in the xz-plane as a mesh, triangulated as `grid::build_grid`
/// triangulates the cloth (each quad split along its p00–p11 diagonal), with uvs: the
/// test of the mesh path against the grid, and what `scenes/make_meshes.py` writes.
pub fn grid_mesh(n: u32, size: f32) -> TriMesh {
    let h = size / (n - 1) as f32;
    let mut positions = Vec::new();
    let mut uvs = Vec::new();
    for j in 0..n {
        for i in 0..n {
            positions.push([i as f32 * h - 0.5 * size, 0.0, j as f32 * h]);
            uvs.push([i as f32 / (n - 1) as f32, j as f32 / (n - 1) as f32]);
        }
    }
    let mut triangles = Vec::new();
    for qj in 0..n - 1 {
        for qi in 0..n - 1 {
            let p00 = qj * n + qi;
            let (p10, p01, p11) = (p00 + 1, p00 + n, p00 + n + 1);
            triangles.push([p00, p01, p11]);
            triangles.push([p00, p11, p10]);
        }
    }
    TriMesh { positions, uvs: Some(uvs), triangles }
}

/// The mesh as OBJ text (positions, uvs when there are, faces 1-based): what a scene's
/// mesh file holds; `parse_obj` reads it back to the same mesh (positions and uvs as
/// `f32`'s shortest round-trip decimals).
pub fn to_obj(mesh: &TriMesh) -> String {
    use std::fmt::Write as _;
    let mut s = String::from("# written by clothlab\n");
    for p in &mesh.positions {
        let _ = writeln!(s, "v {} {} {}", p[0], p[1], p[2]);
    }
    if let Some(uv) = &mesh.uvs {
        for t in uv {
            let _ = writeln!(s, "vt {} {}", t[0], t[1]);
        }
    }
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| i + 1);
        if mesh.uvs.is_some() {
            let _ = writeln!(s, "f {a}/{a} {b}/{b} {c}/{c}");
        } else {
            let _ = writeln!(s, "f {a} {b} {c}");
        }
    }
    s
}

/// A mesh placed in the scene and checked, with its springs: what a scene's cloth holds
/// once its file is read.
#[derive(Debug, Clone, PartialEq)]
pub struct PlacedMesh {
    /// The mesh, placed.
    pub mesh: TriMesh,
    /// Its springs.
    pub springs: MeshSprings,
    /// The mean edge length, m (the grid's spacing for a mesh: bending moduli and
    /// self-collision read it).
    pub spacing: f32,
    /// Per vertex, its index in the file (vertices in no triangle are dropped; pins are
    /// given in the file's numbering).
    pub file_of: Vec<u32>,
    /// The file's vertex count.
    pub file_vertices: usize,
    /// The cloths it is made of, in a scene of several (`[[cloth]]`: one particle array,
    /// a range per cloth); empty for one cloth.
    pub parts: Vec<ClothPart>,
}

/// One cloth of a scene of several: its range of the one particle (and triangle) array
/// and what it brings of its own.
#[derive(Debug, Clone, PartialEq)]
pub struct ClothPart {
    /// What the scene file calls it: `cloth[k]` and, for a mesh, its file's name.
    pub label: String,
    /// Its particles: `first .. first + count` of the array.
    pub first: u32,
    /// How many particles.
    pub count: u32,
    /// Its triangles: `first_triangle .. first_triangle + triangles` of the list.
    pub first_triangle: u32,
    /// How many triangles.
    pub triangles: u32,
    /// Its mass, kg, if it names one (else the parameters' `cloth_mass`).
    pub mass: Option<f32>,
    /// Its free particles' initial velocity, m/s.
    pub velocity: [f32; 3],
    /// Whether it was a grid (simulated as its triangulation in a scene of several).
    pub grid: bool,
}

impl ClothPart {
    /// Its particles' range.
    pub fn range(&self) -> std::ops::Range<usize> {
        self.first as usize..(self.first + self.count) as usize
    }

    /// Its triangles' range.
    pub fn triangle_range(&self) -> std::ops::Range<usize> {
        self.first_triangle as usize..(self.first_triangle + self.triangles) as usize
    }
}

impl PlacedMesh {
    /// `mesh` (checked) moved by `placement`.
    /// Vertices in no triangle are dropped ([`PlacedMesh::dropped`] says how many).
    pub fn new(mesh: &TriMesh, placement: &Placement) -> Result<Self, MeshError> {
        let file_vertices = mesh.positions.len();
        let (mesh, file_of) = mesh.placed(placement).without_unreferenced();
        mesh.check()?;
        let springs = MeshSprings::build(&mesh)?;
        let len =
            |[a, b]: [u32; 2]| glam::Vec3::from(mesh.positions[a as usize]).distance(mesh.positions[b as usize].into());
        let total: f64 = springs.edges.iter().map(|&e| len(e) as f64).sum();
        let spacing = (total / springs.edges.len().max(1) as f64) as f32;
        Ok(Self { mesh, springs, spacing, file_of, file_vertices, parts: Vec::new() })
    }

    /// How many of the file's vertices were in no triangle and dropped.
    pub fn dropped(&self) -> usize {
        self.file_vertices - self.mesh.positions.len()
    }

    /// Per vertex, whether `pinning` holds it, a list of vertices given in the file's
    /// numbering: one that does not exist, or was dropped, is refused.
    pub fn pinned(&self, pinning: &MeshPinning) -> Result<Vec<bool>, MeshError> {
        let MeshPinning::Vertices(list) = pinning else { return self.mesh.pinned(pinning) };
        let mut new_of = vec![None; self.file_vertices];
        for (k, &v) in self.file_of.iter().enumerate() {
            new_of[v as usize] = Some(k as u32);
        }
        let mapped = list
            .iter()
            .map(|&v| match new_of.get(v as usize) {
                None => Err(MeshError::NoSuchPin { vertex: v, count: self.file_vertices }),
                Some(None) => Err(MeshError::DroppedPin(v)),
                Some(Some(k)) => Ok(*k),
            })
            .collect::<Result<Vec<u32>, MeshError>>()?;
        self.mesh.pinned(&MeshPinning::Vertices(mapped))
    }

    /// Reads the mesh file at `path` ([`load_mesh`]: OBJ or glTF, the mesh named `name` of
    /// a glTF file) and places it.
    pub fn load(path: &Path, name: Option<&str>, placement: &Placement) -> Result<Self, MeshFileError> {
        let raw = load_mesh(path, name)?;
        Self::new(&raw, placement).map_err(|error| MeshFileError { path: path.display().to_string(), error })
    }
}

/// Texture coordinates for a mesh without them: the placed positions projected on the two
/// axes along which the mesh is longest, scaled by the longer so the fabric keeps its
/// aspect.
pub fn planar_uvs(mesh: &TriMesh) -> Vec<[f32; 2]> {
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for p in &mesh.positions {
        for c in 0..3 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    let ext = [0, 1, 2].map(|c| hi[c] - lo[c]);
    let mut axes = [0usize, 1, 2];
    axes.sort_by(|&a, &b| ext[b].total_cmp(&ext[a]));
    let (u, v) = (axes[0], axes[1]);
    let scale = 1.0 / ext[u].max(1e-12);
    mesh.positions.iter().map(|p| [(p[u] - lo[u]) * scale, (p[v] - lo[v]) * scale]).collect()
}

#[cfg(test)]
mod tests {
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
