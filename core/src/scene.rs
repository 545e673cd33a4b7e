//! The scene: the cloth's size and placement, the floor, the spheres and boxes it falls on.
//!
//! The default scene is the thesis's: a square cloth held horizontally at its two top
//! corners (the edge `j = 0`), released so that it swings down and drapes over three
//! spheres resting on the floor.

use bytemuck::{Pod, Zeroable};
use serde::{Deserialize, Serialize};

use crate::motion::Motion;
use crate::params::{ParamError, finite_in};

/// Smallest cloth side, particles.
pub const MIN_N: u32 = 2;
/// Largest cloth side, particles (16.7 M particles, about 4.5 GiB of CPU state).
pub const MAX_N: u32 = 4096;
/// Most spheres / boxes a scene may hold (they live in a uniform buffer on the GPU).
pub const MAX_COLLIDERS: usize = 16;
/// The floor height kernels see when a scene has no floor: far below anything a cloth
/// reaches (finite, so that `floor + margin` stays finite).
pub const NO_FLOOR: f32 = -1e30;

/// A sphere collider. `#[repr(C)]`, mirrored in the shaders.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sphere {
    /// Centre, m.
    pub center: [f32; 3],
    /// Radius, m.
    pub radius: f32,
    /// Velocity of the centre at this substep, m/s (w 0): set by [`Scene::colliders_at`]
    /// from the sphere's motion, zero for a still one.
    #[serde(skip)]
    pub velocity: [f32; 4],
    /// Angular velocity about the centre, rad/s (w 0): the surface at `x` moves at
    /// `velocity + spin × (x − center)`.
    #[serde(skip)]
    pub spin: [f32; 4],
}

impl Sphere {
    /// A still sphere.
    pub const fn new(center: [f32; 3], radius: f32) -> Self {
        Self { center, radius, velocity: [0.0; 4], spin: [0.0; 4] }
    }
}

/// An axis-aligned box collider. `#[repr(C)]`, mirrored in the shaders (w unused).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable, Serialize, Deserialize)]
pub struct Aabb {
    /// Lower corner, m (w unused, 0).
    pub min: [f32; 4],
    /// Upper corner, m (w unused, 0).
    pub max: [f32; 4],
    /// Velocity at this substep, m/s (w 0): set by [`Scene::colliders_at`].
    #[serde(skip)]
    pub velocity: [f32; 4],
}

impl Aabb {
    /// A still box from its lower and upper corners.
    pub fn new(min: [f32; 3], max: [f32; 3]) -> Self {
        Self { min: [min[0], min[1], min[2], 0.0], max: [max[0], max[1], max[2], 0.0], velocity: [0.0; 4] }
    }
}

/// The kinds of rod, each a shape about the segment `a`–`b` of a [`Rod`]. A kind is
/// named here, its contact written in `crate::contact` (`Rod`'s `impl Shape`) and in the
/// shaders (`rod_contact`), its picture in `crate::render::rod_mesh`; a scene file's
/// table of its name (`[[capsules]]`) and the shaders' mark (`ROD_CAPSULE`) follow from
/// this list.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RodKind {
    /// A capsule: the points within `radius` of the segment from `a` to `b` (a limb, a
    /// bar).
    Capsule,
    /// A capped cylinder: the points within `radius` of the segment from `a` to `b` that
    /// lie between the planes through `a` and `b` across it (a post, a drum, a table's
    /// round top).
    Cylinder,
    /// A cone: its base the disc of `radius` about `a` across the axis, its apex at `b`
    /// (a lampshade, a traffic cone, a funnel's tip).
    Cone,
}

impl RodKind {
    /// Every kind, in the order a scene file's tables are read (the order of a scene
    /// file's rods in the shapes buffer).
    pub const ALL: [RodKind; 3] = [RodKind::Capsule, RodKind::Cylinder, RodKind::Cone];

    /// Its name (`capsule`; the shaders' mark is `ROD_` and the name in capitals).
    pub fn name(self) -> &'static str {
        match self {
            RodKind::Capsule => "capsule",
            RodKind::Cylinder => "cylinder",
            RodKind::Cone => "cone",
        }
    }

    /// Its scene file's table, and the name of the scene's list of it in messages
    /// (`capsules`).
    pub fn table(self) -> &'static str {
        match self {
            RodKind::Capsule => "capsules",
            RodKind::Cylinder => "cylinders",
            RodKind::Cone => "cones",
        }
    }

    /// What `a` is (for the documentation of a scene file's table).
    pub fn end(self) -> &'static str {
        match self {
            RodKind::Capsule => "one end of the axis",
            RodKind::Cylinder => "the centre of one cap",
            RodKind::Cone => "the centre of the base",
        }
    }

    /// Its mark in `b.w` of its record in the shapes buffer: its place in [`RodKind::ALL`].
    pub fn mark(self) -> f32 {
        self as u32 as f32
    }

    /// Whether its two ends must lie apart (a capsule's may meet: a sphere).
    fn needs_length(self) -> bool {
        !matches!(self, RodKind::Capsule)
    }
}

/// A rod collider: a shape about the segment from `a` to `b` of its [`RodKind`]. Every
/// kind has one record in the shapes buffer ([`RodRecord`], the shaders' `Rod`), one
/// count (`StepParams::num_rods`), one loop in each walk and one motion (`pose_rod`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Rod {
    /// What shape it is.
    pub kind: RodKind,
    /// One end of the axis ([`RodKind::end`]), m; w the radius, m.
    pub a: [f32; 4],
    /// The other end, m (w 0; the shapes buffer marks the kind there).
    pub b: [f32; 4],
    /// Velocity of its centre (the axis' midpoint) at this substep, m/s (w 0).
    #[serde(skip)]
    pub velocity: [f32; 4],
    /// Angular velocity about its centre, rad/s (w 0): the surface at `x` moves at
    /// `velocity + spin × (x − (a + b)/2)`.
    #[serde(skip)]
    pub spin: [f32; 4],
}

/// A rod's record in the shapes buffer (`Buf::Shapes`, from `sdf::RODS_AT`, 16 floats):
/// `#[repr(C)]`, mirrored in the shaders (`Rod`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct RodRecord {
    /// One end, w the radius.
    pub a: [f32; 4],
    /// The other end, w the kind's [`RodKind::mark`].
    pub b: [f32; 4],
    /// Velocity of its centre, w 0.
    pub velocity: [f32; 4],
    /// Angular velocity about its centre, w 0.
    pub spin: [f32; 4],
}

impl Rod {
    /// A still rod of `kind` about the segment `a`–`b`.
    pub fn new(kind: RodKind, a: [f32; 3], b: [f32; 3], radius: f32) -> Self {
        Self { kind, a: [a[0], a[1], a[2], radius], b: [b[0], b[1], b[2], 0.0], velocity: [0.0; 4], spin: [0.0; 4] }
    }

    /// Its radius, m.
    pub fn radius(&self) -> f32 {
        self.a[3]
    }

    /// The axis' midpoint, m, as the kernels compute it (`(a + b)·½`).
    pub fn center(&self) -> [f32; 3] {
        [(self.a[0] + self.b[0]) * 0.5, (self.a[1] + self.b[1]) * 0.5, (self.a[2] + self.b[2]) * 0.5]
    }

    /// Half its axis' length, m.
    pub fn half_length(&self) -> f32 {
        let d: [f32; 3] = std::array::from_fn(|k| self.b[k] - self.a[k]);
        0.5 * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
    }

    /// Its smallest size, m: how far its motion may carry it in a substep
    /// ([`Motion::check_speed`]); a point half of it above its centre lies inside it.
    pub fn size(&self) -> f32 {
        match self.kind {
            RodKind::Capsule => self.radius(),
            RodKind::Cylinder => self.radius().min(self.half_length()),
            // Its radius half way up is half the base's.
            RodKind::Cone => (0.5 * self.radius()).min(self.half_length()),
        }
    }

    /// Its record in the shapes buffer.
    pub fn record(&self) -> RodRecord {
        let mut b = self.b;
        b[3] = self.kind.mark();
        RodRecord { a: self.a, b, velocity: self.velocity, spin: self.spin }
    }
}

/// `rod` where `pose` has it: moved and turned about its centre (in f64, rounded once),
/// with the velocities its contacts use.
fn pose_rod(rod: &mut Rod, pose: &crate::motion::Pose) {
    let Rod { a, b, velocity, spin, .. } = rod;
    let centre =
        glam::DVec3::new(((a[0] + b[0]) * 0.5) as f64, ((a[1] + b[1]) * 0.5) as f64, ((a[2] + b[2]) * 0.5) as f64);
    let offset = glam::DVec3::from(pose.offset.map(f64::from));
    let place = |p: [f32; 4]| {
        let q = glam::DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64) - centre;
        (centre + offset + pose.rotation * q).as_vec3()
    };
    let (na, nb) = (place(*a), place(*b));
    *a = [na.x, na.y, na.z, a[3]];
    *b = [nb.x, nb.y, nb.z, 0.0];
    *velocity = [pose.velocity[0], pose.velocity[1], pose.velocity[2], 0.0];
    *spin = [pose.spin[0], pose.spin[1], pose.spin[2], 0.0];
}

/// Which collider a [`Motion`] moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ColliderId {
    /// `Scene::spheres[i]`.
    Sphere(usize),
    /// `Scene::boxes[i]`.
    Box(usize),
    /// The `i`-th rod of its kind in `Scene::rods` (a scene file's `capsules[i]`).
    Rod(RodKind, usize),
}

impl ColliderId {
    /// Its name in a scene file (`spheres[0]`).
    pub fn field(self) -> String {
        match self {
            ColliderId::Sphere(i) => format!("spheres[{i}]"),
            ColliderId::Box(i) => format!("boxes[{i}]"),
            ColliderId::Rod(kind, i) => format!("{}[{i}]", kind.table()),
        }
    }
}

/// Which particles are held still.
///
/// In a scene file: `"top-corners"`, `"top-edge"`, `"none"`, or a list of grid
/// coordinates `[[i, j], …]` (column `i`, row `j`, both `0 … n-1`).
#[derive(Debug, Clone, PartialEq)]
pub enum Pinning {
    /// The two corners of the top edge (`j = 0`): the thesis's scene.
    TopCorners,
    /// The whole top edge (a curtain).
    TopEdge,
    /// Nothing: the cloth falls freely.
    None,
    /// These particles, as `[i, j]` grid coordinates.
    Points(Vec<[u32; 2]>),
    /// A mesh's vertices, 0-based in the file's order (`{ vertices = [0, 17] }`).
    Vertices(Vec<u32>),
    /// A mesh's vertices below this height once placed, m (`{ below_y = 0.1 }`).
    BelowY(f32),
    /// A mesh's vertices above this height once placed, m (`{ above_y = 1.2 }`).
    AboveY(f32),
}

impl Pinning {
    /// The names a scene file may give.
    pub const NAMES: [&'static str; 3] = ["top-corners", "top-edge", "none"];

    /// Whether particle `(i, j)` of an `n × n` grid is held.
    pub fn holds(&self, n: u32, i: u32, j: u32) -> bool {
        match self {
            Pinning::TopCorners => j == 0 && (i == 0 || i == n - 1),
            Pinning::TopEdge => j == 0,
            Pinning::None => false,
            Pinning::Points(p) => p.contains(&[i, j]),
            Pinning::Vertices(_) | Pinning::BelowY(_) | Pinning::AboveY(_) => false,
        }
    }

    /// A short description for the app and `sim`.
    pub fn label(&self) -> String {
        match self {
            Pinning::TopCorners => "top corners".into(),
            Pinning::TopEdge => "top edge".into(),
            Pinning::None => "none".into(),
            Pinning::Points(p) => format!("{} points", p.len()),
            Pinning::Vertices(v) => format!("{} vertices", v.len()),
            Pinning::BelowY(y) => format!("below y = {y}"),
            Pinning::AboveY(y) => format!("above y = {y}"),
        }
    }
}

impl Serialize for Pinning {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Pinning::TopCorners => s.serialize_str("top-corners"),
            Pinning::TopEdge => s.serialize_str("top-edge"),
            Pinning::None => s.serialize_str("none"),
            Pinning::Points(p) => p.serialize(s),
            Pinning::Vertices(v) => std::collections::BTreeMap::from([("vertices", v)]).serialize(s),
            Pinning::BelowY(y) => std::collections::BTreeMap::from([("below_y", y)]).serialize(s),
            Pinning::AboveY(y) => std::collections::BTreeMap::from([("above_y", y)]).serialize(s),
        }
    }
}

/// A pinned grid point `[i, j]`: exactly two numbers (an array deserialised as
/// `[u32; 2]` takes the first two of a longer one and drops the rest unread).
struct GridPoint([u32; 2]);

impl<'de> Deserialize<'de> for GridPoint {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let v = Vec::<u32>::deserialize(d)?;
        match v[..] {
            [i, j] => Ok(GridPoint([i, j])),
            _ => Err(D::Error::custom(format!("a pinned grid point is [i, j]: two numbers, got {}", v.len()))),
        }
    }
}

impl<'de> Deserialize<'de> for Pinning {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Pinning;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                write!(
                    f,
                    "\"top-corners\", \"top-edge\", \"none\", a list of [i, j] grid points, or for a mesh {{ vertices = [..] }}, {{ below_y = .. }} or {{ above_y = .. }}"
                )
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Pinning, E> {
                match v {
                    "top-corners" => Ok(Pinning::TopCorners),
                    "top-edge" => Ok(Pinning::TopEdge),
                    "none" => Ok(Pinning::None),
                    _ => Err(E::unknown_variant(v, &Pinning::NAMES)),
                }
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Pinning, A::Error> {
                let mut points = Vec::new();
                while let Some(GridPoint(p)) = seq.next_element()? {
                    points.push(p);
                }
                Ok(Pinning::Points(points))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Pinning, A::Error> {
                use serde::de::Error;
                let Some(key) = map.next_key::<String>()? else {
                    return Err(A::Error::custom("an empty table: give one of vertices, below_y, above_y"));
                };
                let pinning = match key.as_str() {
                    "vertices" => Pinning::Vertices(map.next_value()?),
                    "below_y" => Pinning::BelowY(map.next_value()?),
                    "above_y" => Pinning::AboveY(map.next_value()?),
                    _ => return Err(A::Error::unknown_field(&key, &["vertices", "below_y", "above_y"])),
                };
                if map.next_key::<String>()?.is_some() {
                    return Err(A::Error::custom("one rule per cloth: vertices, below_y or above_y"));
                }
                Ok(pinning)
            }
        }
        d.deserialize_any(V)
    }
}

/// The cloth: an `n × n` grid of particles, or a triangle mesh (`mesh`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ClothSpec {
    /// Particles per side. Default 100. Valid: 2 ..= 4096.
    pub n: u32,
    /// Side length of the square cloth, m. Default 2.
    pub size: f32,
    /// Centre of the top edge (`j = 0`), m. Default (0, 2.2, -0.9).
    pub top_center: [f32; 3],
    /// Direction of the rows (increasing `i`): a unit vector. Default +x.
    pub across: [f32; 3],
    /// Direction from the top edge into the cloth (increasing `j`): a unit vector
    /// perpendicular to `across`. Default +z (the cloth starts horizontal); -y hangs it.
    pub down: [f32; 3],
    /// Which particles are pinned. Default [`Pinning::TopCorners`].
    pub pinning: Pinning,
    /// Initial velocity of every free particle, m/s (a thrown cloth). Default 0.
    pub velocity: [f32; 3],
    /// A triangle mesh (OBJ, or glTF: `.glb`, `.gltf`) instead of the grid; a scene file's path is relative to the
    /// file. With a mesh, `n`, `size`, `top_center`, `across` and `down` do not apply.
    pub mesh: Option<std::path::PathBuf>,
    /// With a glTF `mesh`: the name of the mesh to read (default: the file's first
    /// with triangles).
    pub mesh_name: Option<String>,
    /// The mesh's scale per axis (about the origin, first). Default 1.
    pub scale: [f32; 3],
    /// The mesh's rotation about x, then y, then z, degrees. Default 0.
    pub rotate_deg: [f32; 3],
    /// The mesh's translation, m (last). Default 0.
    pub translate: [f32; 3],
    /// In a scene of several cloths (`[[cloth]]`), this cloth's mass, kg. Default: the
    /// parameters' `cloth_mass` (which is the mass of a scene's one cloth).
    pub mass: Option<f32>,
    /// The mesh as read, placed and checked (`SceneFile::load` makes it).
    #[serde(skip)]
    pub mesh_data: Option<std::sync::Arc<crate::mesh::PlacedMesh>>,
}

impl Default for ClothSpec {
    fn default() -> Self {
        Self {
            n: 100,
            size: 2.0,
            top_center: [0.0, 2.2, -0.9],
            across: [1.0, 0.0, 0.0],
            down: [0.0, 0.0, 1.0],
            pinning: Pinning::TopCorners,
            velocity: [0.0; 3],
            mesh: None,
            mesh_name: None,
            scale: [1.0; 3],
            rotate_deg: [0.0; 3],
            translate: [0.0; 3],
            mass: None,
            mesh_data: None,
        }
    }
}

impl ClothSpec {
    /// The mesh's placement.
    pub fn placement(&self) -> crate::mesh::Placement {
        crate::mesh::Placement { scale: self.scale, rotate_deg: self.rotate_deg, translate: self.translate }
    }

    /// Whether the cloth is a mesh.
    pub fn is_mesh(&self) -> bool {
        self.mesh_data.is_some()
    }

    /// Rest position of particle `(i, j)`: `top_center + (i·h − size/2)·across + j·h·down`
    /// with `h = size / (n − 1)`.
    pub fn rest_position(&self, i: u32, j: u32) -> [f32; 3] {
        let h = self.size / (self.n - 1) as f32;
        let (u, v) = (i as f32 * h - 0.5 * self.size, j as f32 * h);
        std::array::from_fn(|k| self.top_center[k] + u * self.across[k] + v * self.down[k])
    }
}

/// The whole scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Scene {
    /// The cloth.
    pub cloth: ClothSpec,
    /// Height of the floor plane, m, or `None`: no floor. Default 0.
    pub floor_y: Option<f32>,
    /// Sphere colliders. Default: three spheres resting on the floor under the cloth.
    pub spheres: Vec<Sphere>,
    /// Axis-aligned box colliders. Default: none.
    pub boxes: Vec<Aabb>,
    /// Rod colliders (capsules, cylinders), in the order the kernels walk them.
    /// Default: none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub rods: Vec<Rod>,
    /// How colliders move (at most one motion each; none: all still). See [`crate::motion`].
    #[serde(default)]
    pub motions: Vec<(ColliderId, Motion)>,
    /// Groups of pinned particles, held where they rest or moved (see [`crate::pins`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub pins: Vec<crate::pins::PinGroup>,
    /// Bodies: colliders from triangle meshes, as distance fields (see [`crate::sdf`];
    /// built when a scene file is read, not serialized).
    #[serde(skip)]
    pub bodies: Vec<crate::sdf::Body>,
}

impl Default for Scene {
    fn default() -> Self {
        Self {
            cloth: ClothSpec::default(),
            floor_y: Some(0.0),
            spheres: vec![
                Sphere::new([-0.55, 0.35, -0.35], 0.35),
                Sphere::new([0.45, 0.45, -0.1], 0.45),
                Sphere::new([-0.05, 0.25, 0.55], 0.25),
            ],
            boxes: Vec::new(),
            rods: Vec::new(),
            motions: Vec::new(),
            pins: Vec::new(),
            bodies: Vec::new(),
        }
    }
}

impl Scene {
    /// The default scene with an `n × n` cloth.
    pub fn with_n(n: u32) -> Self {
        let mut s = Self::default();
        s.cloth.n = n;
        s
    }

    /// Number of particles, `n²`.
    pub fn num_particles(&self) -> usize {
        match &self.cloth.mesh_data {
            Some(m) => m.mesh.positions.len(),
            None => self.cloth.n as usize * self.cloth.n as usize,
        }
    }

    /// The rest distance between neighbouring particles, m: the grid's spacing, or a
    /// mesh's mean edge length (placed).
    pub fn spacing(&self) -> f32 {
        match &self.cloth.mesh_data {
            Some(m) => m.spacing,
            None => self.cloth.size / (self.cloth.n - 1) as f32,
        }
    }

    /// The floor height the kernels test against: far below anything when there is no floor.
    pub fn floor_height(&self) -> f32 {
        self.floor_y.unwrap_or(NO_FLOOR)
    }

    /// Checks the scene; the first bad value is reported, named by its path in a scene
    /// file (`cloth.n`, `spheres[1].radius`).
    pub fn validate(&self) -> Result<(), ParamError> {
        let c = &self.cloth;
        let n = c.n;
        if !(MIN_N..=MAX_N).contains(&n) {
            return Err(ParamError::new("cloth.n", n, format!("grid side must be in {MIN_N} ..= {MAX_N}")));
        }
        finite_in("cloth.size", c.size, 1e-3, 1e3)?;
        for v in c.top_center {
            finite_in("cloth.top_center", v, -1e4, 1e4)?;
        }
        for v in c.velocity {
            finite_in("cloth.velocity", v, -1e3, 1e3)?;
        }
        if let Some(m) = c.mass {
            finite_in("cloth.mass", m, 1e-6, 1e6)?;
        }
        // A direction is a unit vector within 1e-3 of its length, taken as written (a file's
        // [0, -0.9798, 0.2] is 1 + 4e-6 long, [1.0005, 0, 0] 1 + 5e-4); its components are
        // checked only for being finite, so that one a little over 1 is not refused as out
        // of range when the vector is what is meant.
        let unit = |name: &str, a: [f32; 3]| -> Result<f32, ParamError> {
            for v in a {
                finite_in(format!("cloth.{name}"), v, -1e3, 1e3)?;
            }
            let len = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
            if (len - 1.0).abs() > 1e-3 {
                return Err(ParamError::new(
                    format!("cloth.{name}"),
                    format!("{a:?}"),
                    format!("must be a unit vector (its length is {len})"),
                ));
            }
            Ok(len)
        };
        unit("across", c.across)?;
        unit("down", c.down)?;
        let dot: f32 = (0..3).map(|k| c.across[k] * c.down[k]).sum();
        if dot.abs() > 1e-3 {
            return Err(ParamError::new(
                "cloth.down",
                format!("{:?}", c.down),
                format!("must be perpendicular to cloth.across (their dot product is {dot})"),
            ));
        }
        if let Pinning::Points(p) = &c.pinning {
            if p.len() > n as usize * n as usize {
                return Err(ParamError::new("cloth.pinning", p.len(), "more points than particles"));
            }
            if let Some(k) = p.iter().position(|q| q[0] >= n || q[1] >= n) {
                return Err(ParamError::new(
                    format!("cloth.pinning[{k}]"),
                    format!("{:?}", p[k]),
                    format!("a grid point [i, j] needs i, j < n = {n}"),
                ));
            }
        }
        let mesh_rule = matches!(c.pinning, Pinning::Vertices(_) | Pinning::BelowY(_) | Pinning::AboveY(_));
        match (c.mesh.is_some() || c.mesh_data.is_some(), mesh_rule) {
            (false, true) => {
                return Err(ParamError::new(
                    "cloth.pinning",
                    c.pinning.label(),
                    "pins a mesh's vertices; a grid takes \"top-corners\", \"top-edge\", \"none\" or [[i, j], …]",
                ));
            }
            (true, false) if c.pinning != Pinning::None => {
                return Err(ParamError::new(
                    "cloth.pinning",
                    c.pinning.label(),
                    "names grid points; a mesh takes \"none\", { vertices = [..] }, { below_y = .. } or { above_y = .. }",
                ));
            }
            _ => {}
        }
        if let Pinning::BelowY(y) | Pinning::AboveY(y) = c.pinning {
            finite_in("cloth.pinning", y, -1e4, 1e4)?;
        }
        if c.mesh.is_some() || c.mesh_data.is_some() {
            for v in c.scale {
                if !(v.is_finite() && (1e-4..=1e4).contains(&v.abs())) {
                    return Err(ParamError::new("cloth.scale", v, "each factor's size must be in 1e-4 ..= 1e4"));
                }
            }
            for v in c.rotate_deg {
                finite_in("cloth.rotate_deg", v, -3600.0, 3600.0)?;
            }
            for v in c.translate {
                finite_in("cloth.translate", v, -1e4, 1e4)?;
            }
            if c.mesh_data.is_none() {
                return Err(ParamError::new(
                    "cloth.mesh",
                    c.mesh.as_ref().map(|p| p.display().to_string()).unwrap_or_default(),
                    "the mesh was not read (a scene file reads it; in code, `PlacedMesh::load`)",
                ));
            }
        }
        if let Some(y) = self.floor_y {
            finite_in("floor.y", y, -1e4, 1e4)?;
        }
        if self.spheres.len() > MAX_COLLIDERS {
            return Err(ParamError::new("spheres", self.spheres.len(), format!("at most {MAX_COLLIDERS}")));
        }
        if self.boxes.len() > MAX_COLLIDERS {
            return Err(ParamError::new("boxes", self.boxes.len(), format!("at most {MAX_COLLIDERS}")));
        }
        if self.rods.len() > crate::sdf::MAX_RODS {
            let most = crate::sdf::MAX_RODS;
            let kinds = RodKind::ALL.map(RodKind::table).join(", ");
            let field = self.rods.last().map_or("rods", |r| r.kind.table());
            return Err(ParamError::new(field, self.rods.len(), format!("at most {most} rods ({kinds}) together")));
        }
        for (k, r) in self.rods.iter().enumerate() {
            let (kind, i) = (r.kind, self.rank(k));
            let name = kind.table();
            for c in 0..3 {
                finite_in(format!("{name}[{i}].a"), r.a[c], -1e4, 1e4)?;
                finite_in(format!("{name}[{i}].b"), r.b[c], -1e4, 1e4)?;
            }
            finite_in(format!("{name}[{i}].radius"), r.a[3], 1e-4, 1e4)?;
            if kind.needs_length() && r.half_length() < 1e-4 {
                return Err(ParamError::new(
                    format!("{name}[{i}].b"),
                    format!("{:?}", &r.b[..3]),
                    "must lie at least 0.2 mm from a",
                ));
            }
        }
        for (i, s) in self.spheres.iter().enumerate() {
            for v in s.center {
                finite_in(format!("spheres[{i}].center"), v, -1e4, 1e4)?;
            }
            finite_in(format!("spheres[{i}].radius"), s.radius, 1e-4, 1e4)?;
        }
        for (i, b) in self.boxes.iter().enumerate() {
            for k in 0..3 {
                finite_in(format!("boxes[{i}].min"), b.min[k], -1e4, 1e4)?;
                finite_in(format!("boxes[{i}].max"), b.max[k], -1e4, 1e4)?;
                if b.max[k] <= b.min[k] {
                    return Err(ParamError::new(format!("boxes[{i}].max"), b.max[k], "every max must exceed its min"));
                }
            }
        }
        for (k, (id, m)) in self.motions.iter().enumerate() {
            let exists = match *id {
                ColliderId::Sphere(i) => i < self.spheres.len(),
                ColliderId::Box(i) => i < self.boxes.len(),
                ColliderId::Rod(kind, i) => self.rod_index(kind, i).is_some(),
            };
            if !exists {
                return Err(ParamError::new(id.field(), "motion", "moves a collider the scene does not have"));
            }
            if self.motions[..k].iter().any(|(other, _)| other == id) {
                return Err(ParamError::new(id.field(), "motion", "has two motions"));
            }
            m.check(&id.field(), !matches!(id, ColliderId::Box(_)))?;
        }
        if self.pins.len() > crate::pins::MAX_PIN_GROUPS {
            return Err(ParamError::new("pins", self.pins.len(), format!("at most {}", crate::pins::MAX_PIN_GROUPS)));
        }
        for (i, g) in self.pins.iter().enumerate() {
            g.check(i)?;
        }
        if self.bodies.len() > crate::sdf::MAX_BODIES {
            return Err(ParamError::new(
                "bodies",
                self.bodies.len(),
                format!("at most {} bodies", crate::sdf::MAX_BODIES),
            ));
        }
        let points: usize = self.bodies.iter().map(|b| b.sdf.values.len()).sum();
        if points > crate::sdf::MAX_POINTS {
            return Err(ParamError::new(
                "bodies",
                points,
                format!(
                    "the bodies' fields hold more than {} points together: lower their resolution",
                    crate::sdf::MAX_POINTS
                ),
            ));
        }
        for (i, b) in self.bodies.iter().enumerate() {
            b.motion.check(&format!("bodies[{i}]"), true)?;
        }
        Ok(())
    }

    /// Removes a sphere or a box, and its motion; the motions of the colliders after it
    /// follow them to their new indices. Out of range: nothing changes.
    pub fn remove_collider(&mut self, id: ColliderId) {
        match id {
            ColliderId::Sphere(i) if i < self.spheres.len() => {
                self.spheres.remove(i);
            }
            ColliderId::Box(i) if i < self.boxes.len() => {
                self.boxes.remove(i);
            }
            ColliderId::Rod(kind, i) if self.rod_index(kind, i).is_some() => {
                self.rods.remove(self.rod_index(kind, i).unwrap_or_default());
            }
            _ => return,
        }
        self.motions.retain(|(m, _)| *m != id);
        for (m, _) in &mut self.motions {
            match (m, id) {
                (ColliderId::Sphere(k), ColliderId::Sphere(i)) | (ColliderId::Box(k), ColliderId::Box(i)) if *k > i => {
                    *k -= 1
                }
                (ColliderId::Rod(kind, k), ColliderId::Rod(of, i)) if *kind == of && *k > i => *k -= 1,
                _ => {}
            }
        }
    }

    /// Whether any collider moves.
    pub fn moves(&self) -> bool {
        self.motions.iter().any(|(_, m)| !m.is_still()) || self.bodies.iter().any(|b| !b.motion.is_still())
    }

    /// Whether any `[[pins]]` group moves (by its motion, or may by a script's).
    pub fn pins_move(&self) -> bool {
        self.pins.iter().any(|g| g.scripted || !g.motion.is_still())
    }

    /// Whether anything in the scene moves by itself (colliders or pins): what a
    /// recording of several substeps at once (`temporal=on`) cannot follow.
    pub fn animated(&self) -> bool {
        self.moves() || self.pins_move()
    }

    /// Refuses motions faster than a substep of `dt` s resolves ([`Motion::check_speed`]).
    pub fn check_motion_speed(&self, dt: f32) -> Result<(), ParamError> {
        for (id, m) in &self.motions {
            let size = match *id {
                ColliderId::Sphere(i) => self.spheres.get(i).map_or(0.0, |s| s.radius),
                ColliderId::Box(i) => self
                    .boxes
                    .get(i)
                    .map_or(0.0, |b| (0..3).map(|k| 0.5 * (b.max[k] - b.min[k])).fold(f32::INFINITY, f32::min)),
                ColliderId::Rod(kind, i) => self.rod_index(kind, i).map_or(0.0, |k| self.rods[k].size()),
            };
            m.check_speed(&id.field(), size, dt)?;
        }
        for (i, b) in self.bodies.iter().enumerate() {
            b.check_speed(&format!("bodies[{i}]"), dt)?;
        }
        Ok(())
    }

    /// Where the `i`-th rod of `kind` lies in [`Scene::rods`].
    pub fn rod_index(&self, kind: RodKind, i: usize) -> Option<usize> {
        self.rods.iter().enumerate().filter(|(_, r)| r.kind == kind).nth(i).map(|(k, _)| k)
    }

    /// The name of `rods[k]` (the `i`-th of its kind): what a motion moves.
    pub fn rod_id(&self, k: usize) -> ColliderId {
        ColliderId::Rod(self.rods[k].kind, self.rank(k))
    }

    /// How many rods of `rods[k]`'s kind come before it.
    fn rank(&self, k: usize) -> usize {
        self.rods[..k].iter().filter(|r| r.kind == self.rods[k].kind).count()
    }

    /// The rods at simulated time `t`, s: moved and turned about their centres by their
    /// motions (in f64, rounded once), with the velocities their contacts use.
    pub fn rods_at(&self, t: f64, out: &mut Vec<Rod>) {
        out.clone_from(&self.rods);
        for (k, r) in out.iter_mut().enumerate() {
            let id = self.rod_id(k);
            if let Some((_, m)) = self.motions.iter().find(|(m, _)| *m == id) {
                pose_rod(r, &m.at(t));
            }
        }
    }

    /// The leading [`crate::sdf::VALUES_AT`] floats of the GPU's shapes buffer
    /// (`Buf::Shapes`) at time `t`, s: the bodies' heads, then the rods (each marked by its
    /// kind in `b.w`), each region padded with zeros to its most.
    pub fn shapes_at(&self, t: f64) -> Vec<f32> {
        use crate::sdf::{MAX_BODIES, RODS_AT, SdfHead, VALUES_AT};
        let mut out = vec![0.0f32; VALUES_AT];
        let mut heads = Vec::new();
        self.bodies_at(t, &mut heads);
        heads.truncate(MAX_BODIES);
        out[..heads.len() * SdfHead::FLOATS].copy_from_slice(bytemuck::cast_slice(&heads));
        let mut rods = Vec::new();
        self.rods_at(t, &mut rods);
        for (k, rod) in rods.iter().take(crate::sdf::MAX_RODS).enumerate() {
            out[RODS_AT + 16 * k..RODS_AT + 16 * (k + 1)].copy_from_slice(bytemuck::cast_slice(&[rod.record()]));
        }
        out
    }

    /// The bodies' heads at simulated time `t`, s (their poses, velocities and where their
    /// values start among [`crate::sdf::concat`]'s).
    pub fn bodies_at(&self, t: f64, heads: &mut Vec<crate::sdf::SdfHead>) {
        heads.clear();
        let mut first = 0u32;
        for b in &self.bodies {
            heads.push(b.head_at(t, first));
            first += b.sdf.values.len() as u32;
        }
    }

    /// This scene with its colliders where their motions have them at time `t`, s (what
    /// the renderers draw: `set_colliders`).
    pub fn moved_to(&self, t: f64) -> Scene {
        let mut s = self.clone();
        self.colliders_at(t, &mut s.spheres, &mut s.boxes);
        self.rods_at(t, &mut s.rods);
        // A moving body's mesh, posed (its field is left as it was: this scene is drawn,
        // not simulated).
        for b in s.bodies.iter_mut().filter(|b| b.motion != Motion::default()) {
            let mut mesh = (*b.mesh).clone();
            mesh.positions = b.posed_at(t);
            b.mesh = std::sync::Arc::new(mesh);
        }
        s
    }

    /// The spheres and boxes at simulated time `t`, s: moved by their motions, with the
    /// velocities their contacts use. Still colliders come back as placed (velocity 0).
    pub fn colliders_at(&self, t: f64, spheres: &mut Vec<Sphere>, boxes: &mut Vec<Aabb>) {
        spheres.clone_from(&self.spheres);
        boxes.clone_from(&self.boxes);
        for (id, m) in &self.motions {
            let pose = m.at(t);
            let v = [pose.velocity[0], pose.velocity[1], pose.velocity[2], 0.0];
            match *id {
                ColliderId::Sphere(i) => {
                    if let Some(s) = spheres.get_mut(i) {
                        for k in 0..3 {
                            s.center[k] += pose.offset[k];
                        }
                        s.velocity = v;
                        s.spin = [pose.spin[0], pose.spin[1], pose.spin[2], 0.0];
                    }
                }
                ColliderId::Box(i) => {
                    if let Some(b) = boxes.get_mut(i) {
                        for k in 0..3 {
                            b.min[k] += pose.offset[k];
                            b.max[k] += pose.offset[k];
                        }
                        b.velocity = v;
                    }
                }
                // Moved by `rods_at`.
                ColliderId::Rod(..) => {}
            }
        }
    }
}
