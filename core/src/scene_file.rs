//! Scene files: a whole scene — the cloth, the floor, spheres, boxes, capsules, cylinders, bodies
//! (`crate::sdf`), pins (`crate::pins`), the simulation parameters and optionally the
//! camera and the light — in TOML.
//!
//! TOML rather than RON: scene files are written by hand, and TOML is what Rust users
//! already write (`Cargo.toml`): comments, `[tables]` and `[[arrays of tables]]` for the
//! colliders, no Rust type names or tuple syntax to get right. The `toml` crate reports the
//! byte span of every error, which becomes the line and column of the message.
//!
//! ```toml
//! title = "The thesis's scene"
//! [cloth]
//! n = 100
//! size = 2.0
//! top_center = [0.0, 2.2, -0.9]
//! across = [1.0, 0.0, 0.0]     # direction of the rows (i)
//! down = [0.0, 0.0, 1.0]       # from the top edge into the cloth (j); [0, -1, 0] hangs it
//! pinning = "top-corners"      # "top-edge", "none", or [[i, j], …]
//! velocity = [0.0, 0.0, 0.0]   # initial velocity of the free particles, m/s
//! [floor]
//! y = 0.0                      # `enabled = false`: no floor
//! [[spheres]]
//! center = [0.45, 0.45, -0.1]
//! radius = 0.45
//! [[boxes]]
//! min = [-0.5, 0.0, -0.5]
//! max = [0.5, 0.8, 0.5]
//! [[capsules]]                 # the points within `radius` of the segment a–b
//! a = [-0.6, 0.3, 0.4]
//! b = [0.6, 0.3, 0.4]
//! radius = 0.08
//! [[cylinders]]                # capped: the points within `radius` of the axis a–b, between its ends
//! a = [0.0, 0.0, 0.0]
//! b = [0.0, 0.5, 0.0]
//! radius = 0.3
//! [[cones]]                    # the base a disc of `radius` about a, the apex at b
//! a = [1.0, 0.0, 0.0]
//! b = [1.0, 0.6, 0.0]
//! radius = 0.25
//! [[pins]]                     # holds the particles resting in the box; may move
//! min = [-1.1, 2.1, -1.0]      # (see clothlab_core::pins)
//! max = [1.1, 2.3, -0.8]
//! motion = { spin = [0.0, 0.0, 1.0] }
//! [params]                     # any SimParams field; the rest keep their defaults
//! substeps = 16
//! [camera]                     # optional
//! target = [0.0, 0.9, 0.0]
//! distance = 4.8
//! yaw_deg = 34.0
//! pitch_deg = 20.0
//! [light]                      # optional
//! position = [2.0, 5.5, 3.0]
//! ```
//!
//! A missing table or field takes the default of the thesis's scene, except the colliders:
//! a file without `[[spheres]]` has none. Unknown fields are refused (a misspelt field
//! would otherwise be silently ignored).

use std::path::Path;

use serde::Deserialize;
use thiserror::Error;

use crate::camera::OrbitCamera;
use crate::motion::Motion;
use crate::params::{ParamError, SimParams};
use crate::scene::{Aabb, ClothSpec, ColliderId, Rod, RodKind, Scene, Sphere};

/// A scene file, read and checked.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneFile {
    /// The file's `title`, if it has one.
    pub title: Option<String>,
    /// The scene.
    pub scene: Scene,
    /// The simulation parameters: the defaults with the file's `[params]` applied.
    pub params: SimParams,
    /// The camera, if the file sets one.
    pub camera: Option<OrbitCamera>,
    /// The light's position, m, if the file sets one.
    pub light: Option<[f32; 3]>,
    /// The file's `envs`: how many worlds (copies of the scene, stepped together) it
    /// asks for, if it says (1 ..= [`MAX_ENVS`]).
    pub envs: Option<u32>,
    /// `[params]` values given one per world (a list where the parameter takes a number or
    /// a word, a list of lists where it takes a list): each name and its worlds' values,
    /// as `--set` would read them. Not in [`SceneFile::params`], which holds the rest;
    /// the library applies them world by world.
    pub world_params: Vec<WorldList>,
}

/// A parameter's name and its values, one per world ([`SceneFile::world_params`]).
pub type WorldList = (String, Vec<serde_json::Value>);

/// The entries of a `[params]` table `params` that give one value per world (see
/// [`SceneFile::world_params`]), and the table without them; `None` where there are none.
fn world_lists(params: &toml::Table) -> Option<(Vec<WorldList>, toml::Table)> {
    let mut lists = Vec::new();
    let mut rest = params.clone();
    for (name, value) in params {
        let values = serde_json::to_value(value).ok().and_then(|v| crate::params::per_world(name, &v));
        if let Some(values) = values {
            lists.push((name.clone(), values));
            rest.remove(name);
        }
    }
    (!lists.is_empty()).then_some((lists, rest))
}

/// The most worlds a batch may hold (`envs`).
pub const MAX_ENVS: u32 = 65_536;

/// Why a scene file was refused: one line naming the file and, where the problem is in
/// the text, its line and column.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("{file}{}: {message}", at.map(|(l, c)| format!(":{l}:{c}")).unwrap_or_default())]
pub struct SceneFileError {
    /// The file as given.
    pub file: String,
    /// Line and column (1-based) of the problem, where it has one.
    pub at: Option<(usize, usize)>,
    /// What is wrong and what is expected.
    pub message: String,
}

/// The file: `C` is a `[cloth]` table (`ClothSpec`) or `[[cloth]]` tables (`Vec<ClothSpec>`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Repr<C> {
    #[serde(default)]
    title: Option<String>,
    #[serde(default)]
    #[allow(dead_code)]
    description: Option<String>,
    #[serde(default)]
    envs: Option<u32>,
    #[serde(default)]
    cloth: C,
    #[serde(default)]
    floor: FloorRepr,
    #[serde(default)]
    spheres: Vec<SphereRepr>,
    #[serde(default)]
    boxes: Vec<BoxRepr>,
    #[serde(default)]
    capsules: Vec<RodRepr>,
    #[serde(default)]
    cylinders: Vec<RodRepr>,
    #[serde(default)]
    cones: Vec<RodRepr>,
    #[serde(default)]
    pins: Vec<crate::pins::PinGroup>,
    #[serde(default)]
    bodies: Vec<crate::sdf::BodySpec>,
    #[serde(default)]
    params: SimParams,
    #[serde(default)]
    camera: Option<CameraRepr>,
    #[serde(default)]
    light: Option<LightRepr>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
struct FloorRepr {
    enabled: bool,
    y: f32,
}

impl Default for FloorRepr {
    fn default() -> Self {
        Self { enabled: true, y: 0.0 }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SphereRepr {
    center: [f32; 3],
    radius: f32,
    #[serde(default)]
    motion: Option<Motion>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BoxRepr {
    min: [f32; 3],
    max: [f32; 3],
    #[serde(default)]
    motion: Option<Motion>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RodRepr {
    a: [f32; 3],
    b: [f32; 3],
    radius: f32,
    #[serde(default)]
    motion: Option<Motion>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraRepr {
    #[serde(default)]
    target: Option<[f32; 3]>,
    #[serde(default)]
    distance: Option<f32>,
    #[serde(default)]
    yaw_deg: Option<f32>,
    #[serde(default)]
    pitch_deg: Option<f32>,
    #[serde(default)]
    fov_deg: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightRepr {
    position: [f32; 3],
}

impl<C> Repr<C> {
    /// The rods' tables, each with its kind, in [`RodKind::ALL`]'s order.
    fn rods(&self) -> [(RodKind, &[RodRepr]); RodKind::ALL.len()] {
        RodKind::ALL.map(|kind| {
            let rods = match kind {
                RodKind::Capsule => &self.capsules,
                RodKind::Cylinder => &self.cylinders,
                RodKind::Cone => &self.cones,
            };
            (kind, &rods[..])
        })
    }

    /// The file without its cloth table(s), and the cloths (`list` makes them a list).
    fn split(self, list: impl FnOnce(C) -> Vec<ClothSpec>) -> (Repr<()>, Vec<ClothSpec>) {
        let Repr {
            title,
            description,
            envs,
            cloth,
            floor,
            spheres,
            boxes,
            capsules,
            cylinders,
            cones,
            pins,
            bodies,
            params,
            camera,
            light,
        } = self;
        let rest = Repr {
            title,
            description,
            envs,
            cloth: (),
            floor,
            spheres,
            boxes,
            capsules,
            cylinders,
            cones,
            pins,
            bodies,
            params,
            camera,
            light,
        };
        (rest, list(cloth))
    }
}

impl SceneFile {
    /// The keys a scene file may have at its top (the command line's help lists them; a
    /// unit test keeps the list in step with what the parser takes).
    pub const TABLES: [&'static str; 15] = [
        "title",
        "description",
        "envs",
        "cloth",
        "floor",
        "spheres",
        "boxes",
        "capsules",
        "cylinders",
        "cones",
        "pins",
        "bodies",
        "params",
        "camera",
        "light",
    ];

    /// Reads and checks `path`.
    pub fn load(path: &Path) -> Result<Self, SceneFileError> {
        Self::load_with(path, |_| Ok(()))
    }

    /// Reads `path`, applies `adjust` to the file's parameters (a command line's
    /// `--integrator` and `--set`) and checks the result: the parameters' stability
    /// against the cloth is judged with what will run, not with the file's values alone.
    /// An error of `adjust` comes back as the message it gave, without a place in the file.
    pub fn load_with(
        path: &Path,
        adjust: impl FnOnce(&mut SimParams) -> Result<(), String>,
    ) -> Result<Self, SceneFileError> {
        let file = path.display().to_string();
        let text = crate::input::read_text_capped(path, crate::input::SCENE_FILE_MAX_BYTES)
            .map_err(|message| SceneFileError { file: file.clone(), at: None, message })?;
        Self::parse_with(&text, &file, adjust)
    }

    /// Parses and checks the text of a scene file (`file` names it in errors). Every value
    /// is checked before anything is returned: a caller applies all of it or none.
    pub fn parse(text: &str, file: &str) -> Result<Self, SceneFileError> {
        Self::parse_with(text, file, |_| Ok(()))
    }

    /// [`SceneFile::parse`] with `adjust` applied to the file's parameters once they are
    /// checked alone and before they are checked against the cloth ([`SceneFile::load_with`]).
    pub fn parse_with(
        text: &str,
        file: &str,
        adjust: impl FnOnce(&mut SimParams) -> Result<(), String>,
    ) -> Result<Self, SceneFileError> {
        let err = |at: Option<(usize, usize)>, message: String| SceneFileError { file: file.to_owned(), at, message };
        let syntax = |e: toml::de::Error| {
            // The message may run over several lines (a syntax error lists what was
            // expected): one line.
            let mut msg = e.message().lines().map(str::trim).filter(|l| !l.is_empty()).collect::<Vec<_>>().join("; ");
            // toml's recursion limit comes without a place: the most deeply nested line.
            let at = e.span().map(|s| line_col(text, s.start)).or_else(|| {
                msg.push_str(" (tables, arrays or dotted keys nested too deeply)");
                deepest_line(text)
            });
            err(at, msg)
        };
        let refused = |e: ParamError, path: String| {
            let at = locate(text, &path).map(|s| line_col(text, s));
            err(at, format!("`{path}` = {}: {}", e.value, e.reason))
        };
        // `[cloth]`, or `[[cloth]]` tables: several cloths.
        let table = toml::from_str::<toml::Table>(text).ok();
        // A vector of other than three numbers (serde would take the first three of four).
        if let Some((path, len)) = table.as_ref().and_then(|t| wrong_vector(t, "")) {
            let at = locate(text, &path).map(|s| line_col(text, s));
            return Err(err(at, format!("`{path}`: a vector has 3 numbers (x, y, z), this one {len}")));
        }
        let many = table.as_ref().and_then(|t| t.get("cloth")).is_some_and(|c| c.is_array());
        // Per-world `[params]` lists come out first; the rest is read from the table then
        // (its errors without a line: a file with them is read from its text as before).
        let worlds = table.as_ref().and_then(|t| t.get("params")?.as_table()).and_then(world_lists);
        let (mut repr, cloths): (Repr<()>, Vec<ClothSpec>) = match (&worlds, &table) {
            (Some((_, rest)), Some(t)) => {
                let mut t = t.clone();
                t.insert("params".into(), toml::Value::Table(rest.clone()));
                let value = toml::Value::Table(t);
                if many {
                    value.try_into::<Repr<Vec<ClothSpec>>>().map_err(syntax)?.split(|c| c)
                } else {
                    value.try_into::<Repr<ClothSpec>>().map_err(syntax)?.split(|c| vec![c])
                }
            }
            _ if many => toml::from_str::<Repr<Vec<ClothSpec>>>(text).map_err(syntax)?.split(|c| c),
            _ => toml::from_str::<Repr<ClothSpec>>(text).map_err(syntax)?.split(|c| vec![c]),
        };
        let world_params = worlds.map(|(lists, _)| lists).unwrap_or_default();
        if cloths.is_empty() {
            return Err(err(locate(text, "cloth").map(|s| line_col(text, s)), "`cloth`: no cloth in the list".into()));
        }
        let mut loaded = Vec::with_capacity(cloths.len());
        for (k, mut cloth) in cloths.into_iter().enumerate() {
            // Where this cloth's keys are: `cloth.x`, or `cloth[k].x` of several.
            let at_key = if many { format!("cloth[{k}]") } else { "cloth".to_owned() };
            let keys: Vec<String> = table
                .as_ref()
                .and_then(|t| t.get("cloth"))
                .and_then(|c| if many { c.as_array().and_then(|a| a.get(k)) } else { Some(c) })
                .and_then(|c| c.as_table())
                .map(|c| c.keys().cloned().collect())
                .unwrap_or_default();
            if cloth.mass.is_some() && !many {
                let at = locate(text, &format!("{at_key}.mass")).map(|s| line_col(text, s));
                return Err(err(
                    at,
                    "`cloth.mass`: a scene's one cloth weighs `[params] cloth_mass`; `mass` is for each of several `[[cloth]]`"
                        .into(),
                ));
            }
            if let Some(mesh) = cloth.mesh.clone() {
                if let Some(key) =
                    keys.iter().find(|key| ["n", "size", "top_center", "across", "down"].contains(&key.as_str()))
                {
                    let at = locate(text, &format!("{at_key}.{key}")).map(|s| line_col(text, s));
                    return Err(err(
                        at,
                        format!(
                            "`{at_key}.{key}` is the grid's; a mesh cloth is placed by scale, rotate_deg and translate"
                        ),
                    ));
                }
                if !keys.iter().any(|key| key == "pinning") {
                    cloth.pinning = crate::scene::Pinning::None;
                }
                // Relative to the scene file's folder.
                let path = Path::new(file).parent().map(|d| d.join(&mesh)).unwrap_or(mesh);
                let placed = crate::mesh::PlacedMesh::load(&path, cloth.mesh_name.as_deref(), &cloth.placement());
                let at = locate(text, &format!("{at_key}.mesh")).map(|s| line_col(text, s));
                cloth.mesh_data =
                    Some(std::sync::Arc::new(placed.map_err(|e| err(at, format!("`{at_key}.mesh`: {e}")))?));
            }
            loaded.push(cloth);
        }
        let cloth = if many {
            crate::cloth::combine(&loaded).map_err(|e| {
                let path = e.field.clone();
                refused(e, path)
            })?
        } else {
            loaded.remove(0)
        };
        // Bodies: each mesh read, placed and turned into its field (refused in one line).
        let mut bodies = Vec::with_capacity(repr.bodies.len());
        for (i, spec) in repr.bodies.iter().enumerate() {
            let field = format!("bodies[{i}]");
            crate::sdf::check_spec(spec, &field).map_err(|e| {
                let path = e.field.clone();
                refused(e, path)
            })?;
            let at = locate(text, &format!("{field}.mesh")).map(|s| line_col(text, s));
            let path = Path::new(file).parent().map(|d| d.join(&spec.mesh)).unwrap_or(spec.mesh.clone());
            let mesh = crate::mesh::load_mesh(&path, spec.mesh_name.as_deref())
                .map_err(|e| err(at, format!("`{field}.mesh`: {e}")))?;
            let placed = mesh.placed(&spec.placement());
            let resolution = spec.resolution.unwrap_or(crate::sdf::DEFAULT_RESOLUTION);
            let body = crate::sdf::Body::new(
                placed,
                resolution,
                spec.thickness,
                spec.pivot,
                spec.motion.clone().unwrap_or_default(),
            )
            .map_err(|e| err(at, format!("`{field}.mesh` ({}): {e}", spec.mesh.display())))?;
            bodies.push(body);
        }
        let scene = Scene {
            cloth,
            floor_y: repr.floor.enabled.then_some(repr.floor.y),
            spheres: repr.spheres.iter().map(|s| Sphere::new(s.center, s.radius)).collect(),
            boxes: repr.boxes.iter().map(|b| Aabb::new(b.min, b.max)).collect(),
            rods: (repr.rods().into_iter())
                .flat_map(|(kind, rods)| rods.iter().map(move |r| Rod::new(kind, r.a, r.b, r.radius)))
                .collect(),
            motions: (repr.spheres.iter().enumerate())
                .filter_map(|(i, s)| Some((ColliderId::Sphere(i), s.motion.clone()?)))
                .chain(repr.boxes.iter().enumerate().filter_map(|(i, b)| Some((ColliderId::Box(i), b.motion.clone()?))))
                .chain(repr.rods().into_iter().flat_map(|(kind, rods)| {
                    (rods.iter().enumerate())
                        .filter_map(move |(i, c)| Some((ColliderId::Rod(kind, i), c.motion.clone()?)))
                }))
                .collect(),
            pins: repr.pins,
            bodies,
        };
        scene.validate().map_err(|e| {
            let path = e.field.clone();
            refused(e, path)
        })?;
        // The parameters alone, then against the cloth (stability at its particles'
        // masses, the self-collision thickness at its spacing).
        let at_params = |e: ParamError| {
            // A collider's motion too fast for the substeps is the collider's field.
            let own = ["cloth.", "spheres[", "boxes[", "pins[", "bodies["].iter().any(|p| e.field.starts_with(p))
                || RodKind::ALL.iter().any(|k| e.field.starts_with(&format!("{}[", k.table())));
            let path = if own { e.field.clone() } else { format!("params.{}", e.field) };
            refused(e, path)
        };
        repr.params.validate().map_err(at_params)?;
        adjust(&mut repr.params).map_err(|message| err(None, message))?;
        crate::cloth::check_params(&scene, &repr.params).map_err(at_params)?;
        let camera = match repr.camera {
            None => None,
            Some(c) => {
                let mut cam = OrbitCamera::default();
                let check = |name: &str, v: f32, lo: f32, hi: f32| {
                    crate::params::finite_in(format!("camera.{name}"), v, lo, hi).map_err(|e| {
                        let path = e.field.clone();
                        refused(e, path)
                    })
                };
                if let Some(t) = c.target {
                    for v in t {
                        check("target", v, -1e4, 1e4)?;
                    }
                    cam.target = glam::Vec3::from(t);
                }
                if let Some(d) = c.distance {
                    check("distance", d, OrbitCamera::MIN_DISTANCE, OrbitCamera::MAX_DISTANCE)?;
                    cam.distance = d;
                }
                if let Some(y) = c.yaw_deg {
                    check("yaw_deg", y, -3600.0, 3600.0)?;
                    cam.yaw = y.to_radians();
                }
                if let Some(p) = c.pitch_deg {
                    check("pitch_deg", p, -88.0, 88.0)?;
                    cam.pitch = p.to_radians();
                }
                if let Some(f) = c.fov_deg {
                    check("fov_deg", f, 5.0, 150.0)?;
                    cam.fov_y = f.to_radians();
                }
                Some(cam)
            }
        };
        let light = match repr.light {
            None => None,
            Some(l) => {
                for v in l.position {
                    crate::params::finite_in("light.position", v, -1e4, 1e4)
                        .map_err(|e| refused(e, "light.position".into()))?;
                }
                Some(l.position)
            }
        };
        if let Some(e) = repr.envs
            && !(1..=MAX_ENVS).contains(&e)
        {
            let at = locate(text, "envs").map(|s| line_col(text, s));
            return Err(err(at, format!("`envs` = {e}: the worlds a scene holds, 1 ..= {MAX_ENVS}")));
        }
        Ok(Self { title: repr.title, scene, params: repr.params, camera, light, envs: repr.envs, world_params })
    }
}

/// 1-based line and column (in characters) of byte offset `at` of `text`.
fn line_col(text: &str, at: usize) -> (usize, usize) {
    let before = &text[..at.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

/// The line (and column 1) with the most nesting marks (`.`, `[`, `{`) outside strings:
/// where a file that is nested too deeply for the parser is deepest.
fn deepest_line(text: &str) -> Option<(usize, usize)> {
    let depth = |line: &str| {
        let mut quoted = false;
        line.chars()
            .filter(|&c| {
                quoted ^= c == '"';
                !quoted && matches!(c, '.' | '[' | '{')
            })
            .count()
    };
    let (i, _) = text.lines().enumerate().max_by_key(|(i, l)| (depth(l), std::cmp::Reverse(*i)))?;
    Some((i + 1, 1))
}

/// The keys whose values are 3-vectors (`[x, y, z]`) wherever they stand in a scene file:
/// the cloth's placement and velocity, the colliders' points, motions' offsets, spins and
/// velocities, the pins' boxes and pivots, bodies' placements, the camera, the light's position, and
/// the parameters' gravity and wind.
const VEC3_KEYS: [&str; 19] = [
    "top_center",
    "across",
    "down",
    "velocity",
    "scale",
    "rotate_deg",
    "translate",
    "center",
    "min",
    "max",
    "a",
    "b",
    "target",
    "position",
    "offset",
    "spin",
    "pivot",
    "gravity",
    "wind",
];

/// The first value under a [`VEC3_KEYS`] key that is an array of other than three
/// elements: its path (`cloth.across`, `spheres[1].center`) and length.
fn wrong_vector(table: &toml::Table, prefix: &str) -> Option<(String, usize)> {
    let join = |k: &str| if prefix.is_empty() { k.to_owned() } else { format!("{prefix}.{k}") };
    table.iter().find_map(|(k, v)| match v {
        toml::Value::Array(a) if VEC3_KEYS.contains(&k.as_str()) && a.len() != 3 => Some((join(k), a.len())),
        toml::Value::Table(t) => wrong_vector(t, &join(k)),
        toml::Value::Array(a) => a.iter().enumerate().find_map(|(i, e)| match e {
            toml::Value::Table(t) => wrong_vector(t, &format!("{}[{i}]", join(k))),
            _ => None,
        }),
        _ => None,
    })
}

/// Byte offset of the value at `path` (`spheres[1].radius`, `params.gravity.x`) in the
/// TOML `text`: the deepest part of the path the file spells out, or `None` when not even
/// its first key is in the file (a default was refused).
fn locate(text: &str, path: &str) -> Option<usize> {
    let doc = toml::de::DeTable::parse(text).ok()?;
    let mut segments = Vec::new();
    for part in path.split('.') {
        let mut it = part.split('[');
        segments.push(Seg::Key(it.next()?.to_owned()));
        for idx in it {
            segments.push(Seg::Index(idx.trim_end_matches(']').parse().ok()?));
        }
    }
    let mut segs = segments.into_iter();
    let Some(Seg::Key(first)) = segs.next() else { return None };
    let (_, mut value) = doc.get_ref().iter().find(|(k, _)| k.get_ref() == &first)?;
    let mut found = value.span().start;
    for seg in segs {
        let next = match seg {
            Seg::Key(k) => value.get_ref().get(k.as_str()),
            Seg::Index(i) => value.get_ref().get(i),
        };
        match next {
            Some(v) => {
                value = v;
                found = v.span().start;
            }
            None => break,
        }
    }
    Some(found)
}

enum Seg {
    Key(String),
    Index(usize),
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Pinning;

    #[test]
    fn a_full_file_reads_into_the_scene_it_describes() {
        let text = r#"
title = "t"
[cloth]
n = 40
size = 1.5
top_center = [0.0, 2.0, 0.0]
across = [1.0, 0.0, 0.0]
down = [0.0, -1.0, 0.0]
pinning = [[0, 0], [39, 0]]
velocity = [1.5, 0.0, -2.0]
[floor]
enabled = false
[[spheres]]
center = [0.0, 0.5, 0.0]
radius = 0.3
[[boxes]]
min = [-0.5, 0.0, -0.5]
max = [0.5, 0.8, 0.5]
[params]
substeps = 20
integrator = "xpbd"
[camera]
distance = 6.0
[light]
position = [1.0, 4.0, 2.0]
"#;
        let f = SceneFile::parse(text, "t.toml").unwrap();
        assert_eq!(f.title.as_deref(), Some("t"));
        assert_eq!(f.scene.cloth.n, 40);
        assert_eq!(f.scene.cloth.down, [0.0, -1.0, 0.0]);
        assert_eq!(f.scene.cloth.pinning, Pinning::Points(vec![[0, 0], [39, 0]]));
        assert_eq!(f.scene.cloth.velocity, [1.5, 0.0, -2.0]);
        assert_eq!(f.scene.floor_y, None);
        assert_eq!(f.scene.spheres.len(), 1);
        assert_eq!(f.scene.boxes, vec![Aabb::new([-0.5, 0.0, -0.5], [0.5, 0.8, 0.5])]);
        assert_eq!(f.params.substeps, 20);
        assert_eq!(f.params.integrator, crate::params::Integrator::Xpbd);
        // Unset parameters keep their defaults.
        assert_eq!(f.params.strain_limit, SimParams::default().strain_limit);
        assert_eq!(f.camera.as_ref().map(|c| c.distance), Some(6.0));
        assert_eq!(f.light, Some([1.0, 4.0, 2.0]));
    }

    #[test]
    fn an_empty_file_is_the_default_cloth_on_the_floor_with_no_colliders() {
        let f = SceneFile::parse("", "e.toml").unwrap();
        assert_eq!(f.scene.cloth, ClothSpec::default());
        assert_eq!(f.scene.floor_y, Some(0.0));
        assert!(f.scene.spheres.is_empty() && f.scene.boxes.is_empty());
        assert_eq!(f.params, SimParams::default());
    }

    /// Each bad file: (text, the line and column expected, words the message must hold).
    #[test]
    fn a_bad_file_gets_one_line_with_its_line_column_and_what_is_expected() {
        type Case<'a> = (&'a str, Option<(usize, usize)>, &'a [&'a str]);
        let cases: [Case; 17] = [
            // Syntax.
            ("[cloth]\nn = = 3\n", Some((2, 5)), &["b.toml:2:5"]),
            // A misspelt field.
            ("[cloth]\nn = 30\nsiez = 2.0\n", Some((3, 1)), &["unknown field `siez`", "expected"]),
            // A value of the wrong type.
            ("[cloth]\nn = \"big\"\n", Some((2, 5)), &["invalid type", "u32"]),
            // A pinning that is no pinning.
            ("[cloth]\npinning = \"corners\"\n", Some((2, 11)), &["unknown variant `corners`", "top-corners"]),
            // Refused values name the field, and where it is.
            ("[cloth]\nn = 1\n", Some((2, 5)), &["`cloth.n` = 1", "2 ..= 4096"]),
            (
                "[[spheres]]\ncenter = [0, 1, 0]\nradius = 0.5\n[[spheres]]\ncenter = [0, 1, 0]\nradius = -1\n",
                Some((6, 10)),
                &["`spheres[1].radius` = -1"],
            ),
            ("[[boxes]]\nmin = [0, 0, 0]\nmax = [1, -1, 1]\n", Some((3, 7)), &["`boxes[0].max`", "exceed its min"]),
            ("[params]\nsubsteps = 0\n", Some((2, 12)), &["`params.substeps` = 0"]),
            ("[cloth]\nvelocity = [0, 2000, 0]\n", Some((2, 12)), &["`cloth.velocity` = 2000"]),
            ("[cloth]\nn = 8\npinning = [[0, 0], [8, 0]]\n", Some((3, 20)), &["`cloth.pinning[1]`", "i, j < n = 8"]),
            // Motions: keys out of order, a box that spins, a key that is no number, a
            // sphere faster than a substep resolves.
            (
                "[[spheres]]\ncenter = [0, 1, 0]\nradius = 0.5\nmotion = { keys = [{ t = 1, offset = [0, 0, 0] }, { t = 0.5, offset = [1, 0, 0] }] }\n",
                Some((4, 57)),
                &["`spheres[0].motion.keys[1].t` = 0.5", "strictly increasing"],
            ),
            (
                "[[boxes]]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\nmotion = { spin = [0, 1, 0] }\n",
                Some((4, 19)),
                &["`boxes[0].motion.spin`", "not turn"],
            ),
            (
                "[[spheres]]\ncenter = [0, 1, 0]\nradius = 0.5\nmotion = { keys = [{ t = 0, offset = [nan, 0, 0] }] }\n",
                Some((4, 38)),
                &["`spheres[0].motion.keys[0].offset` = NaN"],
            ),
            (
                "[[spheres]]\ncenter = [0, 1, 0]\nradius = 0.05\nmotion = { velocity = [30, 0, 0] }\n",
                Some((4, 10)),
                &["`spheres[0].motion`", "per substep", "params.substeps"],
            ),
            // A pin with three coordinates.
            ("[cloth]\nn = 8\npinning = [[0, 0], [1, 2, 3]]\n", Some((3, 11)), &["[i, j]", "got 3"]),
            // Parameters refused for this cloth (not for every cloth) are the file's too.
            (
                // `substeps` is not in the file: the table that sets the rest.
                "[cloth]\nn = 512\n[params]\nstiffness_units = \"physical\"\n",
                Some((3, 1)),
                &["`params.substeps` = 16", "at n = 512"],
            ),
            (
                "[cloth]\nn = 512\n[params]\nself_collision = true\nself_thickness = 0.5\n",
                Some((5, 18)),
                &["`params.self_thickness` = 0.5", "at most 0.0059 m"],
            ),
        ];
        for (text, at, words) in cases {
            let e = SceneFile::parse(text, "b.toml").expect_err(text);
            let line = e.to_string();
            assert_eq!(e.at, at, "{text:?}: {line}");
            assert!(!line.contains('\n'), "one line: {line}");
            for w in words {
                assert!(line.contains(w), "{text:?}: `{line}` lacks `{w}`");
            }
        }
    }

    #[test]
    fn a_vector_of_other_than_three_numbers_is_refused_where_it_stands() {
        // serde reads the first three numbers of four and drops the fourth: refused, with
        // the line, wherever a 3-vector stands (a cloth, a list of colliders, a motion).
        for (text, path, line) in [
            ("[cloth]\nacross = [1.0, 0.0, 0.0, 0.0]\n", "cloth.across", 2),
            (
                "[[spheres]]\ncenter = [0.0, 1.0, 0.0]\nradius = 0.2\n[[spheres]]\ncenter = [0.0, 1.0]\nradius = 0.2\n",
                "spheres[1].center",
                5,
            ),
            ("[params]\nwind = [1.0, 0.0, 0.0, 2.0, 3.0]\n", "params.wind", 2),
        ] {
            let e = SceneFile::parse(text, "f.toml").unwrap_err();
            let msg = e.to_string();
            assert!(msg.contains(&format!("`{path}`")) && msg.contains("3 numbers"), "{msg}");
            assert_eq!(e.at.map(|a| a.0), Some(line), "{msg}");
            assert!(!msg.contains('\n'), "{msg}");
        }
    }

    #[test]
    fn a_direction_within_its_tolerance_of_unit_length_is_taken_and_one_further_off_names_its_length() {
        // 1.0005 is within 1e-3 of unit length (a component a little over 1 is not out of
        // range for a unit vector); 1.01 is not, and the message says how long it is.
        let ok = SceneFile::parse("[cloth]\nacross = [1.0005, 0.0, 0.0]\n", "f.toml").unwrap();
        assert_eq!(ok.scene.cloth.across, [1.0005, 0.0, 0.0]);
        let e = SceneFile::parse("[cloth]\nacross = [1.01, 0.0, 0.0]\n", "f.toml").unwrap_err().to_string();
        assert!(e.contains("unit vector") && e.contains("1.01"), "{e}");
    }

    #[test]
    fn the_keys_listed_for_the_help_are_the_keys_the_parser_takes() {
        // serde's message for an unknown key lists the keys it knows.
        let e = SceneFile::parse("no_such_key = 1\n", "f.toml").unwrap_err().to_string();
        let known = e.split("expected one of").nth(1).unwrap_or_else(|| panic!("{e}"));
        let mut from_parser: Vec<&str> = known.split(',').map(|k| k.trim().trim_matches('`')).collect();
        let mut listed = SceneFile::TABLES.to_vec();
        from_parser.sort_unstable();
        listed.sort_unstable();
        assert_eq!(from_parser, listed, "{e}");
    }

    #[test]
    fn the_command_line_adjusts_the_parameters_before_they_are_checked_against_the_cloth() {
        // Physical stiffness at n = 128: too stiff for Verlet at 16 substeps, stable under
        // XPBD. Loaded alone the file is refused; with the integrator adjusted, taken.
        let text = "[cloth]\nn = 128\n[params]\nstiffness_units = \"physical\"\n";
        let e = SceneFile::parse(text, "f.toml").unwrap_err().to_string();
        assert!(e.contains("params."), "{e}");
        let xpbd = |p: &mut SimParams| {
            p.integrator = crate::Integrator::Xpbd;
            Ok(())
        };
        let f = SceneFile::parse_with(text, "f.toml", xpbd).unwrap();
        assert_eq!(f.params.integrator, crate::Integrator::Xpbd);
        // An adjustment's own error comes back as its message.
        let e = SceneFile::parse_with(text, "f.toml", |_| Err("bad --set".into())).unwrap_err();
        assert!(e.to_string().contains("bad --set") && e.at.is_none(), "{e}");
    }

    #[test]
    fn a_file_nested_too_deeply_is_refused_with_the_line_where_it_is_deepest() {
        // 600 dotted keys on line 2: toml stops at its recursion limit without a span.
        let text = format!("title = \"deep\"\na{} = 1\n", ".a".repeat(600));
        let e = SceneFile::parse(&text, "f.toml").unwrap_err();
        assert_eq!(e.at, Some((2, 1)), "{e}");
        assert!(e.to_string().contains("nested too deeply") && !e.to_string().contains('\n'), "{e}");
    }
}
