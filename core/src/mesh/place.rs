//! A mesh in the scene: its placement, which vertices are held, the vertices' masses and
//! tethers, a scene's cloths as parts of one array, and the grid as a mesh.

use std::path::Path;

use super::{MeshError, MeshFileError, MeshSprings, TriMesh, load_mesh};
use crate::tables::TETHER_SLOTS;

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
