//! `sim --record out.glb`: the run as binary glTF 2.0, built with gltf-json and written as
//! a `gltf::binary::Glb`.
//!
//! The cloth is one mesh (triangles, uvs, the first frame's positions and normals; in a
//! scene of several cloths a node and mesh each, `cloth[k]`) with a morph target per
//! recorded frame (its positions less the first frame's), and an
//! animation of the mesh's weights with STEP interpolation: at frame k's time target k
//! has weight 1 and every other 0. Blender imports this as shape keys driven by the
//! animation; three.js and glTF viewers play it as is. The colliders are meshes: each
//! sphere (a UV sphere of 24 × 12), each box, and the floor as a square of 10 m; a moving
//! collider's node is animated (translation, and a spinning sphere's rotation about its
//! centre, LINEAR, sampled at the recorded frames' times: `core::motion`).
//!
//! A batch's worlds ([`glb_worlds`]) are recorded side by side: a node `world k` each,
//! placed on a grid (row after row along x, rows along z, a world's width and a quarter
//! apart), holding that world's cloths and its copies of the colliders (the meshes and
//! the motions' samplers shared), over one floor under them all.

use std::borrow::Cow;
use std::collections::BTreeMap;

use anyhow::{Result, bail};
use clothlab_core::{ClothState, ClothTopology, ColliderId, Scene};
use gltf::json;
use json::validation::Checked::Valid;
use json::validation::USize64;

/// The most bytes a `.glb` may hold (its length field is a u32; kept well below).
pub const MAX_GLB_BYTES: u64 = 2 << 30;

/// The recorded frames of one run.
#[derive(Debug, Clone, Default)]
pub struct Recording {
    /// Time of each recorded frame, s.
    pub times: Vec<f32>,
    /// Positions of each recorded frame.
    pub frames: Vec<Vec<[f32; 3]>>,
    /// Normals of the first frame.
    pub normals: Vec<[f32; 3]>,
}

impl Recording {
    /// Bytes a recording of `frames` frames of `particles` particles and `triangles`
    /// triangles will take (morph targets dominate), for refusing a run before it starts.
    pub fn predicted_bytes(frames: u64, particles: u64, triangles: u64) -> u64 {
        frames * particles * 12 + particles * (12 + 12 + 8) + triangles * 12 + frames * frames * 4 + (1 << 20)
    }

    /// Adds the state at time `t`.
    pub fn push(&mut self, t: f32, state: &ClothState) {
        if self.frames.is_empty() {
            self.normals = state.normal.iter().map(|n| [n[0], n[1], n[2]]).collect();
        }
        self.times.push(t);
        self.frames.push(state.pos.iter().map(|p| [p[0], p[1], p[2]]).collect());
    }
}

/// A run's recording as it goes (`sim --record`, [`crate::Sim::record`]; made by
/// [`crate::Sim::recorder`], which checks it all before the run): the first frame and
/// every `every`-th of one world or of every world of a batch, written by
/// [`Recorder::finish`] as one `.glb` ([`glb_worlds`]).
#[derive(Debug)]
pub struct Recorder {
    path: std::path::PathBuf,
    every: u64,
    frame_dt: f32,
    worlds: Vec<usize>,
    recs: Vec<Recording>,
}

impl Recorder {
    /// A recording to `path` (a `.glb` name, writable) of a run of `frames` frames, every
    /// `every`-th kept, of `world` of a batch of `envs` (`None`: every world), whose
    /// worlds' frames last `frame_dt` s each (they must agree to be recorded together) and
    /// hold `particles` particles and `triangles` triangles; refused, naming what, where
    /// it cannot be.
    pub fn new(
        path: &std::path::Path,
        frames: u64,
        every: u32,
        world: Option<usize>,
        frame_dt: &[f32],
        particles: usize,
        triangles: usize,
    ) -> Result<Self> {
        if !path.extension().is_some_and(|e| e.eq_ignore_ascii_case("glb")) {
            bail!("--record {}: a recording is binary glTF, give a .glb file name", path.display());
        }
        if !(1..=1_000_000).contains(&every) {
            bail!("invalid every {every}: must be in 1 ..= 1000000");
        }
        let envs = frame_dt.len();
        let worlds: Vec<usize> = match world {
            Some(k) if k >= envs => {
                bail!("world {k}: the batch has {envs} worlds (0 ..= {})", envs.saturating_sub(1))
            }
            Some(k) => vec![k],
            None => (0..envs).collect(),
        };
        let first = frame_dt[worlds[0]];
        if let Some(&k) = worlds.iter().find(|&&k| frame_dt[k] != first) {
            bail!(
                "--record: world {k}'s frames last {} s, world {}'s {first} s: worlds are recorded together at one frame time; record one (--world)",
                frame_dt[k],
                worlds[0]
            );
        }
        crate::files::check_writable(path)?;
        let kept = 1 + frames / u64::from(every);
        let bytes = worlds.len() as u64 * Recording::predicted_bytes(kept, particles as u64, triangles as u64);
        if bytes > MAX_GLB_BYTES {
            bail!(
                "--record: {kept} frames of {} world(s) of {particles} particles would be {bytes} bytes, more than the {MAX_GLB_BYTES} a .glb may hold; raise --record-every or record one world (--world)",
                worlds.len()
            );
        }
        let recs = vec![Recording::default(); worlds.len()];
        Ok(Self { path: path.to_owned(), every: u64::from(every), frame_dt: first, worlds, recs })
    }

    /// The worlds it records.
    pub fn worlds(&self) -> &[usize] {
        &self.worlds
    }

    /// After frame `frame` of the run (0: before it): each recorded world's state from
    /// `state(k)` (world k's), where the frame is one kept.
    pub fn frame(&mut self, frame: u64, mut state: impl FnMut(usize) -> Result<ClothState>) -> Result<()> {
        if frame.is_multiple_of(self.every) {
            for (rec, &k) in self.recs.iter_mut().zip(&self.worlds) {
                rec.push(frame as f32 * self.frame_dt, &state(k)?);
            }
        }
        Ok(())
    }

    /// Writes the recording (the file whole or not at all); returns its path, the frames
    /// kept and its bytes.
    pub fn finish(self, topo: &ClothTopology, scene: &Scene) -> Result<(std::path::PathBuf, usize, usize)> {
        let bytes = glb_worlds(&self.recs, topo, scene)?;
        crate::files::write_bytes(&self.path, &bytes)?;
        Ok((self.path, self.recs[0].frames.len(), bytes.len()))
    }
}

/// Appends `data` to the binary chunk (4-byte aligned) and returns its view.
fn view(
    root: &mut json::Root,
    bin: &mut Vec<u8>,
    data: &[u8],
    target: Option<json::buffer::Target>,
) -> json::Index<json::buffer::View> {
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let offset = bin.len();
    bin.extend_from_slice(data);
    root.push(json::buffer::View {
        buffer: json::Index::new(0),
        byte_length: USize64::from(data.len()),
        byte_offset: Some(USize64::from(offset)),
        byte_stride: None,
        extensions: Default::default(),
        extras: Default::default(),
        name: None,
        target: target.map(Valid),
    })
}

/// An accessor over a whole view.
fn accessor(
    root: &mut json::Root,
    view: json::Index<json::buffer::View>,
    count: usize,
    component: json::accessor::ComponentType,
    type_: json::accessor::Type,
    bounds: Option<([f32; 3], [f32; 3])>,
) -> json::Index<json::Accessor> {
    root.push(json::Accessor {
        buffer_view: Some(view),
        byte_offset: Some(USize64(0)),
        count: USize64::from(count),
        component_type: Valid(json::accessor::GenericComponentType(component)),
        extensions: Default::default(),
        extras: Default::default(),
        type_: Valid(type_),
        min: bounds.map(|b| json::Value::from(b.0.to_vec())),
        max: bounds.map(|b| json::Value::from(b.1.to_vec())),
        name: None,
        normalized: false,
        sparse: None,
    })
}

fn bounds(points: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::MAX; 3];
    let mut hi = [f32::MIN; 3];
    for p in points {
        for c in 0..3 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    (lo, hi)
}

/// A static mesh node: positions and triangles.
fn static_mesh(
    root: &mut json::Root,
    bin: &mut Vec<u8>,
    name: &str,
    pos: &[[f32; 3]],
    tris: &[[u32; 3]],
) -> json::Index<json::Node> {
    let pv = view(root, bin, bytemuck::cast_slice(pos), Some(json::buffer::Target::ArrayBuffer));
    let pa = accessor(
        root,
        pv,
        pos.len(),
        json::accessor::ComponentType::F32,
        json::accessor::Type::Vec3,
        Some(bounds(pos)),
    );
    let iv = view(root, bin, bytemuck::cast_slice(tris), Some(json::buffer::Target::ElementArrayBuffer));
    let ia = accessor(root, iv, 3 * tris.len(), json::accessor::ComponentType::U32, json::accessor::Type::Scalar, None);
    let primitive = json::mesh::Primitive {
        attributes: BTreeMap::from([(Valid(json::mesh::Semantic::Positions), pa)]),
        extensions: Default::default(),
        extras: Default::default(),
        indices: Some(ia),
        material: None,
        mode: Valid(json::mesh::Mode::Triangles),
        targets: None,
    };
    let mesh = root.push(json::Mesh {
        extensions: Default::default(),
        extras: Default::default(),
        name: Some(name.into()),
        primitives: vec![primitive],
        weights: None,
    });
    root.push(json::Node { mesh: Some(mesh), name: Some(name.into()), ..Default::default() })
}

/// A UV sphere around `c` of radius `r`, counter-clockwise seen from outside.
fn sphere_mesh(c: [f32; 3], r: f32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let (around, rings) = (24u32, 12u32);
    let mut pos = Vec::new();
    for j in 0..=rings {
        let th = std::f32::consts::PI * j as f32 / rings as f32;
        for i in 0..around {
            let ph = std::f32::consts::TAU * i as f32 / around as f32;
            pos.push([c[0] + r * th.sin() * ph.cos(), c[1] + r * th.cos(), c[2] + r * th.sin() * ph.sin()]);
        }
    }
    let mut tris = Vec::new();
    for j in 0..rings {
        for i in 0..around {
            let a = j * around + i;
            let b = j * around + (i + 1) % around;
            let (a2, b2) = (a + around, b + around);
            tris.push([a, b, b2]);
            tris.push([a, b2, a2]);
        }
    }
    (pos, tris)
}

/// Rod `rod` about its centre (`clothlab_core::render::rod_mesh`).
fn rod_local(rod: &clothlab_core::Rod) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let (m, mut local) = (rod.center(), *rod);
    for (k, m) in m.into_iter().enumerate() {
        local.a[k] -= m;
        local.b[k] -= m;
    }
    let (pos, _, tris) = clothlab_core::render::rod_mesh(&local, 24);
    (pos, tris)
}

/// An axis-aligned box's 8 corners and 12 triangles, counter-clockwise from outside.
fn box_mesh(lo: [f32; 3], hi: [f32; 3]) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let pos: Vec<[f32; 3]> = (0..8)
        .map(|k| {
            [
                if k & 1 == 0 { lo[0] } else { hi[0] },
                if k & 2 == 0 { lo[1] } else { hi[1] },
                if k & 4 == 0 { lo[2] } else { hi[2] },
            ]
        })
        .collect();
    // Faces as quads (a, b, c, d) counter-clockwise from outside.
    let quads = [[0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7, 3], [0, 2, 3, 1], [4, 5, 7, 6]];
    let tris = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
    (pos, tris)
}

/// The recording as `.glb` bytes.
pub fn glb(rec: &Recording, topo: &ClothTopology, scene: &Scene) -> Result<Vec<u8>> {
    glb_worlds(std::slice::from_ref(rec), topo, scene)
}

/// The recordings of a batch's worlds (recorded at the same times, world 0 first) as one
/// `.glb`, laid out on a grid; of one world, [`glb`]'s bytes.
pub fn glb_worlds(recs: &[Recording], topo: &ClothTopology, scene: &Scene) -> Result<Vec<u8>> {
    let Some(rec) = recs.first() else { bail!("--record: no world was recorded") };
    let Some(base) = rec.frames.first() else { bail!("--record: no frame was recorded") };
    if let Some(k) = recs.iter().position(|r| r.times != rec.times || r.frames.len() != rec.frames.len()) {
        bail!("--record: world {k} was recorded at other times than world 0; record one world (--world)");
    }
    let predicted = recs.len() as u64
        * Recording::predicted_bytes(rec.frames.len() as u64, base.len() as u64, topo.triangles.len() as u64);
    if predicted > MAX_GLB_BYTES {
        bail!(
            "--record: {predicted} bytes, more than the {MAX_GLB_BYTES} a .glb may hold; record fewer frames (--record-every)"
        );
    }
    let mut root = json::Root::default();
    let mut bin: Vec<u8> = Vec::new();
    use json::accessor::{ComponentType as C, Type as T};
    let t = json::buffer::Target::ArrayBuffer;

    // The cloths: a node each (one for a scene's one cloth; `cloth[k]` of several), with
    // its base positions, normals, uvs, triangles and a target per frame.
    let frames = rec.frames.len();
    let whole = [(String::from("cloth"), 0..base.len(), 0..topo.triangles.len())];
    let parts: Vec<(String, std::ops::Range<usize>, std::ops::Range<usize>)> = match topo.parts() {
        [] => whole.to_vec(),
        parts => {
            parts.iter().enumerate().map(|(k, p)| (format!("cloth[{k}]"), p.range(), p.triangle_range())).collect()
        }
    };
    // Each world's cloths (`world_cloths[w]`); the uvs and triangles are the first world's.
    let worlds = recs.len();
    let mut world_cloths = vec![Vec::with_capacity(parts.len()); worlds];
    let mut shared = vec![None; parts.len()];
    for ((w, rec), (p, (name, range, tris))) in
        recs.iter().enumerate().flat_map(|w| parts.iter().cloned().enumerate().map(move |p| (w, p)))
    {
        let name = if worlds > 1 { format!("world {w} {name}") } else { name };
        let base = &rec.frames[0][range.clone()];
        let pv = view(&mut root, &mut bin, bytemuck::cast_slice(base), Some(t));
        let positions = accessor(&mut root, pv, base.len(), C::F32, T::Vec3, Some(bounds(base)));
        let nv = view(&mut root, &mut bin, bytemuck::cast_slice(&rec.normals[range.clone()]), Some(t));
        let normals = accessor(&mut root, nv, range.len(), C::F32, T::Vec3, None);
        let (uvs, indices) = *shared[p].get_or_insert_with(|| {
            let uv = view(&mut root, &mut bin, bytemuck::cast_slice(&topo.uv[range.clone()]), Some(t));
            let uvs = accessor(&mut root, uv, range.len(), C::F32, T::Vec2, None);
            let first = range.start as u32;
            let local: Vec<[u32; 3]> = topo.triangles[tris].iter().map(|t| t.map(|v| v - first)).collect();
            let iv =
                view(&mut root, &mut bin, bytemuck::cast_slice(&local), Some(json::buffer::Target::ElementArrayBuffer));
            (uvs, accessor(&mut root, iv, 3 * local.len(), C::U32, T::Scalar, None))
        });
        let mut targets = Vec::with_capacity(frames);
        for frame in &rec.frames {
            let d: Vec<[f32; 3]> =
                frame[range.clone()].iter().zip(base).map(|(p, b)| [p[0] - b[0], p[1] - b[1], p[2] - b[2]]).collect();
            let dv = view(&mut root, &mut bin, bytemuck::cast_slice(&d), Some(t));
            let da = accessor(&mut root, dv, d.len(), C::F32, T::Vec3, Some(bounds(&d)));
            targets.push(json::mesh::MorphTarget { positions: Some(da), normals: None, tangents: None });
        }
        let primitive = json::mesh::Primitive {
            attributes: BTreeMap::from([
                (Valid(json::mesh::Semantic::Positions), positions),
                (Valid(json::mesh::Semantic::Normals), normals),
                (Valid(json::mesh::Semantic::TexCoords(0)), uvs),
            ]),
            extensions: Default::default(),
            extras: Default::default(),
            indices: Some(indices),
            material: None,
            mode: Valid(json::mesh::Mode::Triangles),
            targets: Some(targets),
        };
        let mut weights0 = vec![0.0f32; frames];
        weights0[0] = 1.0;
        let mesh = root.push(json::Mesh {
            extensions: Default::default(),
            extras: Default::default(),
            name: Some(name.clone()),
            primitives: vec![primitive],
            weights: Some(weights0),
        });
        world_cloths[w].push(root.push(json::Node { mesh: Some(mesh), name: Some(name), ..Default::default() }));
    }

    // The animation: at frame k's time, target k alone (STEP).
    let tv = view(&mut root, &mut bin, bytemuck::cast_slice(&rec.times), None);
    let t_last = *rec.times.last().unwrap_or(&0.0);
    let input = root.push(json::Accessor {
        min: Some(json::Value::from(vec![rec.times[0]])),
        max: Some(json::Value::from(vec![t_last])),
        ..json_accessor(tv, frames, T::Scalar)
    });
    let mut w = vec![0.0f32; frames * frames];
    for k in 0..frames {
        w[k * frames + k] = 1.0;
    }
    let wv = view(&mut root, &mut bin, bytemuck::cast_slice(&w), None);
    let output = root.push(json_accessor(wv, frames * frames, T::Scalar));
    let sampler = json::animation::Sampler {
        extensions: Default::default(),
        extras: Default::default(),
        input,
        interpolation: Valid(json::animation::Interpolation::Step),
        output,
    };
    // Moving colliders: their nodes' translation (and a spinning sphere's or body's
    // rotation about its centre or pivot) at every recorded frame's time, LINEAR.
    let mut samplers = vec![sampler];
    let mut moving = Vec::new();
    // Spheres and boxes that move, then every body (a mesh about its pivot: its node
    // placed there, and moved and turned where its motion says).
    let colliders = scene.motions.iter().filter_map(|(id, m)| {
        Some(match *id {
            ColliderId::Sphere(k) => {
                let s = scene.spheres.get(k)?;
                // The mesh around the node's origin, so that a rotation turns it in place.
                (Some(*id), format!("sphere {k}"), s.center, sphere_mesh([0.0; 3], s.radius), m)
            }
            ColliderId::Box(k) => {
                let b = scene.boxes.get(k)?;
                let (lo, hi) = ([b.min[0], b.min[1], b.min[2]], [b.max[0], b.max[1], b.max[2]]);
                (Some(*id), format!("box {k}"), [0.0; 3], box_mesh(lo, hi), m)
            }
            ColliderId::Rod(kind, k) => {
                let c = &scene.rods[scene.rod_index(kind, k)?];
                // About its centre, which the motion moves and turns it about.
                (Some(*id), format!("{} {k}", kind.name()), c.center(), rod_local(c), m)
            }
        })
    });
    let bodies = scene.bodies.iter().enumerate().map(|(k, b)| {
        let local = b.mesh.positions.iter().map(|p| [0, 1, 2].map(|c| p[c] - b.pivot[c])).collect();
        (None, format!("body {k}"), b.pivot, (local, b.mesh.triangles.clone()), &b.motion)
    });
    let mut body_nodes = Vec::new();
    for (id, name, place, mesh, m) in colliders.chain(bodies) {
        let node = static_mesh(&mut root, &mut bin, &name, &mesh.0, &mesh.1);
        let poses: Vec<_> = rec.times.iter().map(|&t| m.at(t as f64)).collect();
        let at =
            |p: &clothlab_core::motion::Pose| [place[0] + p.offset[0], place[1] + p.offset[1], place[2] + p.offset[2]];
        root.nodes[node.value()].translation = Some(at(&poses[0]));
        if id.is_none() {
            body_nodes.push(node);
            // A still body may stand turned by its keys: placed so, not animated.
            let turn = poses[0].rotation.as_quat();
            if turn != glam::Quat::IDENTITY {
                root.nodes[node.value()].rotation = Some(json::scene::UnitQuaternion(turn.to_array()));
            }
            if m.is_still() {
                continue;
            }
        }
        let tr: Vec<[f32; 3]> = poses.iter().map(at).collect();
        let tv = view(&mut root, &mut bin, bytemuck::cast_slice(&tr), None);
        let output = root.push(json_accessor(tv, tr.len(), T::Vec3));
        let linear = |output| json::animation::Sampler {
            extensions: Default::default(),
            extras: Default::default(),
            input,
            interpolation: Valid(json::animation::Interpolation::Linear),
            output,
        };
        samplers.push(linear(output));
        let mut channels = vec![(node, samplers.len() - 1, json::animation::Property::Translation)];
        if m.spin != [0.0; 3] || m.keys_turn() {
            // Its turn at each frame (a spin's by ω t, or the keys'), as a quaternion.
            let q: Vec<[f32; 4]> = poses.iter().map(|p| p.rotation.as_quat().to_array()).collect();
            root.nodes[node.value()].rotation = Some(json::scene::UnitQuaternion(q[0]));
            let qv = view(&mut root, &mut bin, bytemuck::cast_slice(&q), None);
            let output = root.push(json_accessor(qv, q.len(), T::Vec4));
            samplers.push(linear(output));
            channels.push((node, samplers.len() - 1, json::animation::Property::Rotation));
        }
        moving.push((id, node, channels));
    }
    // The colliders (the moving ones made above): world 0's.
    let mut colliders = Vec::new();
    let moved = |id: ColliderId| moving.iter().find(|m| m.0 == Some(id)).map(|m| m.1);
    for (k, s) in scene.spheres.iter().enumerate() {
        if let Some(node) = moved(ColliderId::Sphere(k)) {
            colliders.push(node);
            continue;
        }
        let (p, t) = sphere_mesh(s.center, s.radius);
        colliders.push(static_mesh(&mut root, &mut bin, &format!("sphere {k}"), &p, &t));
    }
    for (k, b) in scene.boxes.iter().enumerate() {
        if let Some(node) = moved(ColliderId::Box(k)) {
            colliders.push(node);
            continue;
        }
        let lo = [b.min[0], b.min[1], b.min[2]];
        let hi = [b.max[0], b.max[1], b.max[2]];
        let (p, t) = box_mesh(lo, hi);
        colliders.push(static_mesh(&mut root, &mut bin, &format!("box {k}"), &p, &t));
    }
    // The rods, each about its centre.
    let rods = scene.rods.iter().enumerate().map(|(k, c)| {
        let i = scene.rods[..k].iter().filter(|o| o.kind == c.kind).count();
        (scene.rod_id(k), format!("{} {i}", c.kind.name()), c.center(), rod_local(c))
    });
    for (id, name, centre, (p, t)) in rods {
        if let Some(node) = moved(id) {
            colliders.push(node);
            continue;
        }
        let node = static_mesh(&mut root, &mut bin, &name, &p, &t);
        root.nodes[node.value()].translation = Some(centre);
        colliders.push(node);
    }
    colliders.extend(body_nodes);
    // Every other world's copies of them: the same meshes, moved by the same samplers.
    let mut copies = vec![colliders.clone()];
    for w in 1..worlds {
        copies.push(
            colliders
                .iter()
                .map(|n| {
                    let mut node = root.nodes[n.value()].clone();
                    node.name = node.name.map(|name| format!("world {w} {name}"));
                    root.push(node)
                })
                .collect(),
        );
    }
    let mut collider_channels = Vec::new();
    for copy in &copies {
        for (_, node, channels) in &moving {
            let at = colliders.iter().position(|n| n == node).expect("a moving collider is one of the colliders");
            for &(_, sampler, property) in channels {
                collider_channels.push(json::animation::Channel {
                    sampler: json::Index::new(sampler as u32),
                    target: json::animation::Target {
                        extensions: Default::default(),
                        extras: Default::default(),
                        node: copy[at],
                        path: Valid(property),
                    },
                    extensions: Default::default(),
                    extras: Default::default(),
                });
            }
        }
    }
    root.push(json::Animation {
        extensions: Default::default(),
        extras: Default::default(),
        // Every cloth's weights from the one sampler, then the colliders' motions.
        channels: world_cloths
            .iter()
            .flatten()
            .map(|&node| json::animation::Channel {
                sampler: json::Index::new(0),
                target: json::animation::Target {
                    extensions: Default::default(),
                    extras: Default::default(),
                    node,
                    path: Valid(json::animation::Property::MorphTargetWeights),
                },
                extensions: Default::default(),
                extras: Default::default(),
            })
            .chain(collider_channels)
            .collect(),
        name: Some("simulation".into()),
        samplers,
    });

    // One world: its nodes at the root. Several: a node each on the grid, holding its
    // cloths and colliders.
    let mut nodes = Vec::new();
    let (offsets, floor) = layout(recs, scene);
    if worlds == 1 {
        nodes.extend(world_cloths.concat());
        nodes.extend(colliders);
    } else {
        for (w, (cloths, copy)) in world_cloths.into_iter().zip(copies).enumerate() {
            nodes.push(root.push(json::Node {
                name: Some(format!("world {w}")),
                translation: Some(offsets[w]),
                children: Some(cloths.into_iter().chain(copy).collect()),
                ..Default::default()
            }));
        }
    }
    if let Some(y) = scene.floor_y {
        let ([x0, z0], [x1, z1]) = floor;
        let p = [[x0, y, z0], [x1, y, z0], [x1, y, z1], [x0, y, z1]];
        nodes.push(static_mesh(&mut root, &mut bin, "floor", &p, &[[0, 2, 1], [0, 3, 2]]));
    }
    root.push(json::Scene { extensions: Default::default(), extras: Default::default(), name: None, nodes });
    root.scene = Some(json::Index::new(0));
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    root.push(json::Buffer {
        byte_length: USize64::from(bin.len()),
        extensions: Default::default(),
        extras: Default::default(),
        name: None,
        uri: None,
    });
    let mut text = json::serialize::to_vec(&root)?;
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let length = 12 + 8 + text.len() + 8 + bin.len();
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header { magic: *b"glTF", version: 2, length: u32::try_from(length)? },
        json: Cow::Owned(text),
        bin: Some(Cow::Owned(bin)),
    };
    Ok(glb.to_vec()?)
}

/// A square on the floor: its corners' (x, z), the least and the most.
type Square = ([f32; 2], [f32; 2]);

/// Where each world goes ([`glb_worlds`]) and the floor's square `([x0, z0], [x1, z1])`
/// under them. One world stays where it is on a floor 10 m square about the origin.
/// Several go on a grid (the fewest columns whose square holds them, row after row along
/// x, rows along z) as far apart as a world is wide and a quarter more: a world's width
/// is the most, along x or z, that its cloths spread over the recorded frames or its
/// colliders reach where their motions have them at those frames (`Scene::moved_to`:
/// each shape's `Shape::bound`, each body's posed mesh), and the floor reaches 5 m past
/// the outer worlds.
fn layout(recs: &[Recording], scene: &Scene) -> (Vec<[f32; 3]>, Square) {
    let worlds = recs.len();
    if worlds <= 1 {
        return (vec![[0.0; 3]; worlds], ([-5.0, -5.0], [5.0, 5.0]));
    }
    use clothlab_core::contact::{Bound, Shape};
    let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
    let mut take = |p: glam::Vec3, r: f32| {
        if p.is_finite() {
            for (k, c) in [p.x, p.z].into_iter().enumerate() {
                lo[k] = lo[k].min(c - r);
                hi[k] = hi[k].max(c + r);
            }
        }
    };
    for p in recs.iter().flat_map(|r| r.frames.iter().flatten()) {
        take(glam::Vec3::from(*p), 0.0);
    }
    // Still colliders are where they are at any time: one look.
    let moving = !scene.motions.is_empty() || scene.bodies.iter().any(|b| !b.motion.is_still());
    let times = &recs[0].times[..if moving { recs[0].times.len() } else { recs[0].times.len().min(1) }];
    for &t in times {
        let at = scene.moved_to(f64::from(t));
        let shapes = at.spheres.iter().map(|c| c.bound(0.0));
        for b in shapes.chain(at.boxes.iter().map(|c| c.bound(0.0))).chain(at.rods.iter().map(|c| c.bound(0.0))) {
            match b {
                Bound::Ball { center, r } => take(center, r),
                Bound::Box { lo, hi } => {
                    take(lo, 0.0);
                    take(hi, 0.0);
                }
            }
        }
        for p in at.bodies.iter().flat_map(|b| b.mesh.positions.iter()) {
            take(glam::Vec3::from(*p), 0.0);
        }
    }
    if !(lo[0] <= hi[0] && lo[1] <= hi[1]) {
        return (vec![[0.0; 3]; worlds], ([-5.0, -5.0], [5.0, 5.0]));
    }
    let width = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(0.1);
    let step = 1.25 * width;
    let cols = (1..).find(|c: &usize| c * c >= worlds).unwrap_or(1);
    let offsets: Vec<[f32; 3]> =
        (0..worlds).map(|w| [(w % cols) as f32 * step, 0.0, (w / cols) as f32 * step]).collect();
    let rows = worlds.div_ceil(cols);
    let far = [(cols - 1) as f32 * step, (rows - 1) as f32 * step];
    (offsets, ([lo[0] - 5.0, lo[1] - 5.0], [hi[0] + far[0] + 5.0, hi[1] + far[1] + 5.0]))
}

/// A float accessor over a whole view, without bounds.
fn json_accessor(view: json::Index<json::buffer::View>, count: usize, type_: json::accessor::Type) -> json::Accessor {
    json::Accessor {
        buffer_view: Some(view),
        byte_offset: Some(USize64(0)),
        count: USize64::from(count),
        component_type: Valid(json::accessor::GenericComponentType(json::accessor::ComponentType::F32)),
        extensions: Default::default(),
        extras: Default::default(),
        type_: Valid(type_),
        min: None,
        max: None,
        name: None,
        normalized: false,
        sparse: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_recording_reads_back_with_its_positions_animation_and_colliders() {
        let scene = Scene::with_n(6);
        let params = clothlab_core::SimParams::default();
        let (mut state, topo) = clothlab_core::build(&scene, &params).unwrap();
        let mut rec = Recording::default();
        for k in 0..4 {
            // Three frames after the first, each moved down by 0.1 m and sideways by k mm.
            rec.push(k as f32 / 60.0, &state);
            for p in &mut state.pos {
                p[1] -= 0.1;
                p[0] += 0.001 * k as f32;
            }
        }
        let bytes = glb(&rec, &topo, &scene).unwrap();
        let (doc, buffers, _) = gltf::import_slice(&bytes).unwrap();
        let get = |b: gltf::Buffer<'_>| Some(&buffers[b.index()][..]);
        let mut names: Vec<String> = doc.nodes().filter_map(|n| n.name().map(String::from)).collect();
        names.sort();
        assert_eq!(names, ["cloth", "floor", "sphere 0", "sphere 1", "sphere 2"]);
        let cloth = doc.meshes().find(|m| m.name() == Some("cloth")).unwrap();
        let prim = cloth.primitives().next().unwrap();
        let r = prim.reader(get);
        let base: Vec<[f32; 3]> = r.read_positions().unwrap().collect();
        assert_eq!(base.len(), 36);
        assert_eq!(r.read_indices().unwrap().into_u32().count(), 3 * topo.triangles.len());
        assert_eq!(r.read_tex_coords(0).unwrap().into_f32().count(), 36);
        // Base plus target k is frame k, to the float (a subtraction and an addition of
        // values near 2 m: within 2 ulps, 5e-7 m).
        for (k, (tp, _, _)) in r.read_morph_targets().enumerate() {
            let d: Vec<[f32; 3]> = tp.unwrap().collect();
            for ((b, d), want) in base.iter().zip(&d).zip(&rec.frames[k]) {
                for c in 0..3 {
                    assert!((b[c] + d[c] - want[c]).abs() <= 5e-7, "frame {k}: {} vs {}", b[c] + d[c], want[c]);
                }
            }
        }
        // One animation of the weights, STEP, a key per frame at its time.
        let anim = doc.animations().next().unwrap();
        let ch = anim.channels().next().unwrap();
        assert_eq!(ch.target().property(), gltf::animation::Property::MorphTargetWeights);
        assert_eq!(ch.sampler().interpolation(), gltf::animation::Interpolation::Step);
        let cr = ch.reader(get);
        let times: Vec<f32> = cr.read_inputs().unwrap().collect();
        assert_eq!(times, rec.times);
        let gltf::animation::util::ReadOutputs::MorphTargetWeights(w) = cr.read_outputs().unwrap() else { panic!() };
        let w: Vec<f32> = w.into_f32().collect();
        assert_eq!(w.len(), 16);
        assert!(w.iter().enumerate().all(|(i, v)| *v == if i % 5 == 0 { 1.0 } else { 0.0 }));
    }

    #[test]
    fn moving_colliders_are_recorded_as_node_animations() {
        // Sphere 1 slides at 0.6 m/s along x and spins at 3 rad/s about y; box 0 is keyed
        // up by 0.2 m over 0.05 s. Four frames 1/60 s apart: the node's translation at frame
        // k is its placed centre plus the motion's offset (to the float: 1e-6 m), its
        // rotation a turn of 3·t about y (1e-6).
        use clothlab_core::{Aabb, Key, Motion};
        let mut scene = Scene::with_n(6);
        scene.boxes.push(Aabb::new([1.0, 0.0, 0.0], [1.5, 0.5, 0.5]));
        let keys = vec![Key::new(0.0, [0.0; 3]), Key::new(0.05, [0.0, 0.2, 0.0])];
        scene.motions = vec![
            (ColliderId::Sphere(1), Motion { velocity: [0.6, 0.0, 0.0], spin: [0.0, 3.0, 0.0], ..Motion::default() }),
            (ColliderId::Box(0), Motion { keys, ..Motion::default() }),
        ];
        let params = clothlab_core::SimParams::default();
        let (state, topo) = clothlab_core::build(&scene, &params).unwrap();
        let mut rec = Recording::default();
        for k in 0..4 {
            rec.push(k as f32 / 60.0, &state);
        }
        let bytes = glb(&rec, &topo, &scene).unwrap();
        let (doc, buffers, _) = gltf::import_slice(&bytes).unwrap();
        let get = |b: gltf::Buffer<'_>| Some(&buffers[b.index()][..]);
        let anim = doc.animations().next().unwrap();
        let channel = |node: &str, prop: gltf::animation::Property| {
            anim.channels().find(|c| c.target().node().name() == Some(node) && c.target().property() == prop)
        };
        let c = scene.spheres[1].center;
        let ch = channel("sphere 1", gltf::animation::Property::Translation).expect("the sphere's translation");
        let gltf::animation::util::ReadOutputs::Translations(tr) = ch.reader(get).read_outputs().unwrap() else {
            panic!()
        };
        for (k, p) in tr.enumerate() {
            let want = [c[0] + 0.6 * rec.times[k], c[1], c[2]];
            assert!((0..3).all(|i| (p[i] - want[i]).abs() < 1e-6), "frame {k}: {p:?} vs {want:?}");
        }
        let ch = channel("sphere 1", gltf::animation::Property::Rotation).expect("the sphere's spin");
        let gltf::animation::util::ReadOutputs::Rotations(q) = ch.reader(get).read_outputs().unwrap() else { panic!() };
        for (k, q) in q.into_f32().enumerate() {
            let half = 1.5 * rec.times[k];
            let want = [0.0, half.sin(), 0.0, half.cos()];
            assert!((0..4).all(|i| (q[i] - want[i]).abs() < 1e-6), "frame {k}: {q:?} vs {want:?}");
        }
        let ch = channel("box 0", gltf::animation::Property::Translation).expect("the box's keys");
        let gltf::animation::util::ReadOutputs::Translations(tr) = ch.reader(get).read_outputs().unwrap() else {
            panic!()
        };
        let ys: Vec<f32> = tr.map(|p| p[1]).collect();
        let want = [0.0, 0.2 / 3.0, 0.4 / 3.0, 0.2];
        assert!(ys.iter().zip(want).all(|(y, w)| (y - w).abs() < 1e-6), "{ys:?}");
        // Still colliders stay unanimated.
        assert!(channel("sphere 0", gltf::animation::Property::Translation).is_none());
    }

    #[test]
    fn bodies_are_recorded_as_meshes_about_their_pivots_turning_with_their_motion() {
        // Two bodies of one tetrahedron: the first turning at 2 rad/s about y through its
        // pivot, the second still. Each is a mesh whose vertices are the placed mesh's less
        // the pivot, in a node at the pivot; the turning one's rotation at frame k is the
        // turn 2·t about y (1e-6), so that node · mesh is the body where the solver has it.
        use clothlab_core::Motion;
        use clothlab_core::mesh::TriMesh;
        use clothlab_core::sdf::Body;
        let tet = TriMesh {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            uvs: None,
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        };
        let mut scene = Scene::with_n(6);
        let spin = Motion { spin: [0.0, 2.0, 0.0], ..Motion::default() };
        scene.bodies = vec![
            Body::new(tet.clone(), 8, None, Some([0.5, 0.0, 0.0]), spin).unwrap(),
            Body::new(tet, 8, None, None, Motion::default()).unwrap(),
        ];
        let params = clothlab_core::SimParams::default();
        let (state, topo) = clothlab_core::build(&scene, &params).unwrap();
        let mut rec = Recording::default();
        for k in 0..3 {
            rec.push(k as f32 / 30.0, &state);
        }
        let bytes = glb(&rec, &topo, &scene).unwrap();
        let (doc, buffers, _) = gltf::import_slice(&bytes).unwrap();
        let get = |b: gltf::Buffer<'_>| Some(&buffers[b.index()][..]);
        let node = |name: &str| doc.nodes().find(|n| n.name() == Some(name)).unwrap_or_else(|| panic!("{name}"));
        let b0 = node("body 0");
        assert_eq!(b0.transform().decomposed().0, [0.5, 0.0, 0.0]);
        let prim = b0.mesh().unwrap().primitives().next().unwrap();
        let first = prim.reader(get).read_positions().unwrap().next().unwrap();
        assert_eq!(first, [-0.5, 0.0, 0.0], "vertex 0 less the pivot");
        let anim = doc.animations().next().unwrap();
        let ch = anim
            .channels()
            .find(|c| {
                c.target().node().name() == Some("body 0")
                    && c.target().property() == gltf::animation::Property::Rotation
            })
            .expect("the body's turn");
        let gltf::animation::util::ReadOutputs::Rotations(q) = ch.reader(get).read_outputs().unwrap() else { panic!() };
        for (k, q) in q.into_f32().enumerate() {
            let half = rec.times[k];
            let want = [0.0, half.sin(), 0.0, half.cos()];
            assert!((0..4).all(|i| (q[i] - want[i]).abs() < 1e-6), "frame {k}: {q:?} vs {want:?}");
        }
        // The still body: placed, not animated.
        let b1 = node("body 1");
        assert!(anim.channels().all(|c| c.target().node().index() != b1.index()));
        assert!(doc.scenes().next().unwrap().nodes().any(|n| n.index() == b1.index()));
    }

    #[test]
    fn a_recording_too_big_for_a_glb_is_refused() {
        // 4000 frames of a 512² cloth: 12.6 GB of targets.
        assert!(Recording::predicted_bytes(4000, 512 * 512, 2 * 511 * 511) > MAX_GLB_BYTES);
        assert!(Recording::predicted_bytes(100, 100 * 100, 2 * 99 * 99) < MAX_GLB_BYTES);
    }

    #[test]
    fn a_batchs_worlds_each_move_their_own_copy_of_a_moving_collider_by_the_shared_sampler() {
        // Two worlds, sphere 1 sliding at 0.6 m/s: each world's node holds a copy of it
        // whose translation channel reads the same sampler (the same keys), and the
        // worlds stand apart by more than the scene is wide (1.25 of it).
        use clothlab_core::Motion;
        let mut scene = Scene::with_n(6);
        scene.motions = vec![(ColliderId::Sphere(1), Motion { velocity: [0.6, 0.0, 0.0], ..Motion::default() })];
        let params = clothlab_core::SimParams::default();
        let (mut state, topo) = clothlab_core::build(&scene, &params).unwrap();
        let recs: Vec<Recording> = (0..2)
            .map(|w| {
                let mut rec = Recording::default();
                for k in 0..3 {
                    rec.push(k as f32 / 60.0, &state);
                    state.pos.iter_mut().for_each(|p| p[1] -= 0.01 * (w + 1) as f32);
                }
                rec
            })
            .collect();
        let bytes = glb_worlds(&recs, &topo, &scene).unwrap();
        let (doc, _, _) = gltf::import_slice(&bytes).unwrap();
        let anim = doc.animations().next().unwrap();
        let moving: Vec<(String, usize)> = anim
            .channels()
            .filter(|c| c.target().property() == gltf::animation::Property::Translation)
            .map(|c| (c.target().node().name().unwrap().to_string(), c.sampler().index()))
            .collect();
        assert_eq!(moving.len(), 2, "{moving:?}");
        assert_eq!((moving[0].0.as_str(), moving[1].0.as_str()), ("sphere 1", "world 1 sphere 1"));
        assert_eq!(moving[0].1, moving[1].1, "one sampler for both worlds' sphere");
        let weights =
            anim.channels().filter(|c| c.target().property() == gltf::animation::Property::MorphTargetWeights);
        assert_eq!(weights.count(), 2, "a weights channel per world's cloth");
        let at = |k: usize| {
            let n = doc.nodes().find(|n| n.name() == Some(&format!("world {k}"))).unwrap();
            n.transform().decomposed().0
        };
        let (l, _) = layout(&recs, &scene);
        assert_eq!([at(0), at(1)], [l[0], l[1]]);
        // The cloth, 2 m square, is the widest thing in the scene (the spheres lie under
        // it, the sliding one moves 2 cm): the worlds stand 1.25 × 2 m apart along x.
        assert_eq!(at(1)[0] - at(0)[0], 2.5, "{:?} {:?}", at(0), at(1));
        assert_eq!((at(0)[2], at(1)[2]), (0.0, 0.0), "two worlds: one row");
        // And the worlds' recordings must share their times.
        let mut other = recs.clone();
        other[1].times[2] += 0.01;
        let err = glb_worlds(&other, &topo, &scene).unwrap_err().to_string();
        assert!(err.contains("world 1 was recorded at other times"), "{err}");
    }
}
