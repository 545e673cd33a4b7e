//! Reading a mesh: OBJ (by this crate's reader, which keeps the file's vertex numbering)
//! and glTF, each file's errors with its name; and writing a mesh as OBJ.

use std::path::Path;

use thiserror::Error;

use super::{MAX_MESH_BYTES, MAX_MESH_VERTICES, MeshError, TriMesh};

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
