//! Building a cloth: the grid (`grid::build_grid`) or a mesh (`build_mesh`), whichever
//! the scene holds.

use crate::grid::{ClothState, ClothTopology, MeshTables, Rows, Spring, SpringKind, SpringSlot, TETHER_SLOTS, Tether};
use crate::mesh::{MeshError, MeshPinning, PlacedMesh, Placement, grid_mesh, planar_uvs};
use crate::params::{ParamError, SimParams};
use crate::scene::{ClothSpec, Pinning, Scene};

/// Builds the initial state and the topology for a validated scene and parameters: the
/// grid, or the scene's mesh.
pub fn build(scene: &Scene, params: &SimParams) -> Result<(ClothState, ClothTopology), ParamError> {
    scene.check_motion_speed(params.dt())?;
    match &scene.cloth.mesh_data {
        Some(mesh) => {
            scene.validate()?;
            params.validate()?;
            build_mesh(&scene.cloth, &scene.pins, mesh, params)
        }
        None => crate::grid::build_grid(scene, params),
    }
}

/// What [`build`] would refuse of `params` for `scene`'s cloth (the stability of the
/// springs at its particles' masses, the self-collision thickness), without building a
/// grid's tables: a scene file checks its `[params]` against its cloth with it, so that a
/// refusal can name the file's line.
pub fn check_params(scene: &Scene, params: &SimParams) -> Result<(), ParamError> {
    scene.check_motion_speed(params.dt())?;
    match &scene.cloth.mesh_data {
        Some(_) => build(scene, params).map(|_| ()),
        None => {
            let c = &scene.cloth;
            if !scene.pins.is_empty() {
                // A group that holds no particle is refused here, as at build.
                let rest: Vec<[f32; 4]> = (0..c.n)
                    .flat_map(|j| (0..c.n).map(move |i| (i, j)))
                    .map(|(i, j)| {
                        let [x, y, z] = c.rest_position(i, j);
                        [x, y, z, 1.0]
                    })
                    .collect();
                crate::pins::select(&scene.pins, &rest)?;
            }
            params.validate_for(c.n, c.size / (c.n - 1) as f32)
        }
    }
}

/// Builds the state and topology of a cloth made from `placed` (the scene's mesh):
/// particles at its vertices with masses from their areas (`pos.w` the reference mass
/// `cloth_mass / count` over the vertex's, 0 pinned), the springs in the gather table
/// (edges first, bending springs after) and the flat list (sorted by XPBD pass: `MeshTables::xpbd_passes`),
/// each with the constants of its family for its lighter end, face slots in triangle
/// order, tethers to the two nearest pins.
pub fn build_mesh(
    spec: &ClothSpec,
    groups: &[crate::pins::PinGroup],
    placed: &PlacedMesh,
    params: &SimParams,
) -> Result<(ClothState, ClothTopology), ParamError> {
    let file = spec.mesh.as_ref().map(|p| p.display().to_string()).unwrap_or_else(|| "(mesh)".into());
    let err = |e: MeshError| ParamError::new("cloth.mesh", &file, e.to_string());
    let mesh = &placed.mesh;
    let np = mesh.positions.len();
    let rule = match &spec.pinning {
        Pinning::Vertices(v) => MeshPinning::Vertices(v.clone()),
        Pinning::BelowY(y) => MeshPinning::BelowY(*y),
        Pinning::AboveY(y) => MeshPinning::AboveY(*y),
        _ => MeshPinning::None,
    };
    let mut held = placed.pinned(&rule).map_err(err)?;
    // The `[[pins]]` groups hold the vertices in their boxes too.
    let rest: Vec<[f32; 4]> = mesh.positions.iter().map(|p| [p[0], p[1], p[2], 1.0]).collect();
    let group_of = crate::pins::select(groups, &rest)?;
    for (h, g) in held.iter_mut().zip(&group_of) {
        *h |= g.is_some();
    }
    let moving_pins = crate::pins::moving(groups, &group_of, &rest);
    // Each cloth of several weighs its own mass (or the parameters' cloth_mass), shared
    // by area among its vertices; one cloth weighs cloth_mass.
    let mass = match placed.parts.as_slice() {
        [] => mesh.vertex_masses(params.cloth_mass),
        parts => {
            let areas = mesh.vertex_areas();
            let mut mass = vec![0.0f32; np];
            for part in parts {
                let r = part.range();
                let total: f32 = areas[r.clone()].iter().sum();
                let m = part.mass.unwrap_or(params.cloth_mass);
                for k in r {
                    mass[k] = m * areas[k] / total;
                }
            }
            mass
        }
    };
    // pos.w is this over the vertex's mass: the kernels' mean mass (StepParams::
    // particle_mass) for every cloth, whatever each weighs.
    let reference = params.cloth_mass / np as f32;
    let part_of: Option<Vec<u32>> = (!placed.parts.is_empty()).then(|| {
        let mut of = vec![0u32; np];
        for (k, part) in placed.parts.iter().enumerate() {
            of[part.range()].iter_mut().for_each(|p| *p = k as u32);
        }
        of
    });
    let velocity_of = |k: usize| match &part_of {
        Some(of) => placed.parts[of[k] as usize].velocity,
        None => spec.velocity,
    };
    let free = mass.iter().zip(&held).filter(|(_, h)| !**h).map(|(m, _)| *m);
    let min_mass = free.fold(f32::INFINITY, f32::min);
    let min_mass = if min_mass.is_finite() { min_mass } else { reference };
    params.validate_for_mass(min_mass, placed.spacing, "for this mesh")?;

    let mut pos = Vec::with_capacity(np);
    let mut vel = Vec::with_capacity(np);
    for (k, p) in mesh.positions.iter().enumerate() {
        let w = if held[k] { 0.0 } else { reference / mass[k] };
        pos.push([p[0], p[1], p[2], w]);
        let v0 = velocity_of(k);
        vel.push(if held[k] { [0.0; 4] } else { [v0[0], v0[1], v0[2], 0.0] });
    }
    let uv = mesh.uvs.clone().unwrap_or_else(|| planar_uvs(mesh));

    // Each vertex's triangles in triangle order, as many as it has.
    let mut faces: Vec<Vec<i32>> = vec![Vec::new(); np];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for &v in tri {
            faces[v as usize].push(t as i32);
        }
    }
    let face_slots = Rows::compressed(&faces, None);

    let ms = &placed.springs;
    let dist =
        |a: u32, b: u32| glam::Vec3::from(mesh.positions[a as usize]).distance(mesh.positions[b as usize].into());
    let kind_of = |k: u32| if ms.is_edge(k) { SpringKind::Structural } else { SpringKind::Bend };
    // Each vertex's row: its edges (the head, which the strain limit holds), then its
    // bending springs, in the order `MeshSprings` lists them.
    let rows: Vec<Vec<SpringSlot>> = ms
        .slots
        .iter()
        .enumerate()
        .map(|(v, list)| {
            let slot = |&k: &u32| {
                let other = ms.other(k, v as u32);
                SpringSlot { neighbor: other as i32, rest: dist(v as u32, other), ks: 0.0, kd: 0.0 }
            };
            list.iter().map(slot).collect()
        })
        .collect();
    let heads: Vec<usize> = ms.slots.iter().map(|list| list.iter().filter(|&&k| ms.is_edge(k)).count()).collect();
    let slots = Rows::compressed(&rows, Some(&heads));
    let slot_kind = ms.slots.iter().flatten().map(|&k| kind_of(k)).collect();
    let springs: Vec<Spring> = (0..(ms.edges.len() + ms.bends.len()) as u32)
        .map(|k| {
            let [a, b] = ms.spring(k);
            Spring { a, b, rest: dist(a, b), ks: 0.0, kd: 0.0, kind: kind_of(k) as u32 }
        })
        .collect();
    // The list sorted by XPBD pass, so that a pass is a range of it (one dispatch each).
    let passes = xpbd_colouring(&springs, np);
    let mut xpbd_passes = vec![0u32];
    let springs: Vec<Spring> = passes
        .iter()
        .flat_map(|pass| {
            xpbd_passes.push(xpbd_passes.last().copied().unwrap_or(0) + pass.len() as u32);
            pass.iter().map(|&k| springs[k as usize])
        })
        .collect();
    let tethers = mesh
        .tethers(&held, part_of.as_deref())
        .into_iter()
        .map(|list| {
            let mut t = [Tether::EMPTY; TETHER_SLOTS];
            for (slot, (pin, rest)) in t.iter_mut().zip(list) {
                *slot = Tether { pin: pin as i32, rest };
            }
            t
        })
        .collect();
    let zero = vec![[0.0f32; 4]; np];
    let state = ClothState { n: 0, pos, vel, force: zero.clone(), normal: zero };
    let closest_unsprung = closest_unsprung(&slots, &mesh.positions);
    params.check_mesh(np, closest_unsprung)?;
    // Measured only for the contact between triangles (a search over the whole mesh: 0.03–0.1 s
    // of a mesh scene's start that the other modes would pay for nothing).
    let closest_primitives =
        params.self_collision.triangles().then(|| crate::tri_contact::closest_pair(&state.pos, &mesh.triangles));
    if let Some(closest) = closest_primitives {
        params.check_triangles(closest, "this mesh's")?;
    }
    let parts = placed.parts.clone();
    let tables = MeshTables { slot_kind, mass, min_mass, xpbd_passes, closest_unsprung, closest_primitives, parts };
    let mut topo = ClothTopology {
        n: 0,
        uv,
        triangles: mesh.triangles.clone(),
        slots,
        springs,
        face_slots,
        tethers,
        spacing: placed.spacing,
        mesh: Some(std::sync::Arc::new(tables)),
        colours: Default::default(),
        pins: moving_pins,
        edges: Default::default(),
    };
    // VBD's colouring (cpu::vbd::colouring computes the same).
    let greedy =
        crate::tables::Colours::greedy(np, |i| topo.slots.row(i).iter().filter_map(|s| s.other()).collect::<Vec<_>>());
    topo.colours = std::sync::Arc::new(crate::tables::Colours::from_lists(&greedy));
    topo.set_spring_constants(params);
    Ok((state, topo))
}

/// XPBD's passes over a mesh's springs (`springs`, edges then bending springs): coloured
/// greedily so that no two springs of a pass share a particle, the bending springs'
/// passes first and the edges' last (the grid's order: an iteration ends with the
/// springs the strain is measured on). A pass lists spring indices, ascending.
fn xpbd_colouring(springs: &[Spring], particles: usize) -> Vec<Vec<u32>> {
    let mut passes = Vec::new();
    for bend in [true, false] {
        // Per particle, the colours of this family already touching it (a vertex of
        // valence d needs up to 2d − 1 of them: more than a word's bits on a fan).
        let mut used: Vec<Vec<usize>> = vec![Vec::new(); particles];
        let mut family: Vec<Vec<u32>> = Vec::new();
        for (k, s) in springs.iter().enumerate() {
            if (s.kind == SpringKind::Bend as u32) != bend {
                continue;
            }
            let (a, b) = (s.a as usize, s.b as usize);
            // The first colour neither end has.
            let c = (0..).find(|c| !used[a].contains(c) && !used[b].contains(c)).unwrap_or(0);
            used[a].push(c);
            used[b].push(c);
            if family.len() <= c {
                family.resize(c + 1, Vec::new());
            }
            family[c].push(k as u32);
        }
        passes.extend(family);
    }
    passes
}

/// The smallest rest distance between a particle and one two springs away that shares no
/// spring with it (`slots`: the gather table; `positions`: the rest positions), m;
/// infinite for a mesh with no such pair. Farther pairs are farther apart on any mesh
/// whose triangles are not folded onto each other.
fn closest_unsprung(slots: &Rows<SpringSlot>, positions: &[[f32; 3]]) -> f32 {
    let others = |v: usize| slots.row(v).iter().filter_map(SpringSlot::other);
    let mut closest = f32::INFINITY;
    for v in 0..positions.len() {
        let x = glam::Vec3::from(positions[v]);
        for u in others(v) {
            for w in others(u) {
                if w != v && !others(v).any(|o| o == w) {
                    closest = closest.min(x.distance(positions[w].into()));
                }
            }
        }
    }
    closest
}

/// The most cloths a scene may hold (`[[cloth]]`).
pub const MAX_CLOTHS: usize = 64;

/// The cloths of a scene of several (`[[cloth]]`, each checked as a scene's one cloth is,
/// meshes already read and placed) as the one cloth the solvers run: one particle array
/// and one triangle list, the cloths' ranges in [`crate::mesh::ClothPart`]s. A grid is
/// its triangulation (`grid_mesh`'s, at its place: the same particles and triangles; its
/// springs a mesh's — along and across the edges — not the grid's 12-slot stencil), so
/// every cloth runs on the mesh kernels; pins, velocities and masses stay each cloth's.
/// A refusal names the cloth (`cloth[1].pinning`).
pub fn combine(cloths: &[ClothSpec]) -> Result<ClothSpec, ParamError> {
    use crate::mesh::{ClothPart, TriMesh};
    if cloths.len() > MAX_CLOTHS {
        return Err(ParamError::new("cloth", cloths.len(), format!("a scene holds at most {MAX_CLOTHS} cloths")));
    }
    let at = |k: usize, e: ParamError| ParamError { field: e.field.replacen("cloth", &format!("cloth[{k}]"), 1), ..e };
    let mut all = TriMesh { positions: Vec::new(), uvs: Some(Vec::new()), triangles: Vec::new() };
    let mut held = Vec::new();
    let mut parts = Vec::new();
    for (k, c) in cloths.iter().enumerate() {
        let one = Scene {
            cloth: c.clone(),
            floor_y: None,
            spheres: Vec::new(),
            boxes: Vec::new(),
            rods: Vec::new(),
            motions: Vec::new(),
            pins: Vec::new(),
            bodies: Vec::new(),
        };
        one.validate().map_err(|e| at(k, e))?;
        let (mesh, pins, label) = match &c.mesh_data {
            Some(placed) => {
                let rule = match &c.pinning {
                    Pinning::Vertices(v) => MeshPinning::Vertices(v.clone()),
                    Pinning::BelowY(y) => MeshPinning::BelowY(*y),
                    Pinning::AboveY(y) => MeshPinning::AboveY(*y),
                    _ => MeshPinning::None,
                };
                let pins = placed
                    .pinned(&rule)
                    .map_err(|e| ParamError::new(format!("cloth[{k}].pinning"), c.pinning.label(), e.to_string()))?;
                let name = c.mesh.as_ref().map(|m| m.display().to_string()).unwrap_or_default();
                let mut mesh = placed.mesh.clone();
                mesh.uvs = Some(mesh.uvs.clone().unwrap_or_else(|| planar_uvs(&mesh)));
                (mesh, pins, format!("cloth[{k}] ({name})"))
            }
            None => {
                let n = c.n;
                let mut mesh = grid_mesh(n, c.size);
                mesh.positions = (0..n * n).map(|p| c.rest_position(p % n, p / n)).collect();
                let pins = (0..n * n).map(|p| c.pinning.holds(n, p % n, p / n)).collect();
                (mesh, pins, format!("cloth[{k}] (grid {n} × {n})"))
            }
        };
        let first = all.positions.len() as u32;
        parts.push(ClothPart {
            label,
            first,
            count: mesh.positions.len() as u32,
            first_triangle: all.triangles.len() as u32,
            triangles: mesh.triangles.len() as u32,
            mass: c.mass,
            velocity: c.velocity,
            grid: c.mesh_data.is_none(),
        });
        all.positions.extend_from_slice(&mesh.positions);
        if let Some(u) = all.uvs.as_mut() {
            u.extend(mesh.uvs.iter().flatten());
        }
        all.triangles.extend(mesh.triangles.iter().map(|t| t.map(|v| v + first)));
        held.extend(pins);
    }
    let mut placed = PlacedMesh::new(&all, &Placement::default())
        .map_err(|e| ParamError::new("cloth", format!("{} cloths", cloths.len()), e.to_string()))?;
    placed.parts = parts;
    let pinned = (0..held.len() as u32).filter(|&v| held[v as usize]).collect();
    Ok(ClothSpec {
        mesh: Some(format!("{} cloths", cloths.len()).into()),
        pinning: Pinning::Vertices(pinned),
        mesh_data: Some(std::sync::Arc::new(placed)),
        ..ClothSpec::default()
    })
}

/// The grid of `grid` (an n × n cloth lying in the xz-plane, held at its top corners: the
/// default scene's) as a mesh: `grid_mesh` placed where the grid starts, the same
/// vertices in the same order, the same triangles, held at the same two corners; the
/// colliders and floor kept. What `bench --mesh-vs-grid` and the grid-against-mesh tests
/// compare. Another orientation or pinning, or a mesh already, is refused.
pub fn grid_as_mesh(grid: &Scene) -> Result<Scene, ParamError> {
    let c = &grid.cloth;
    if c.is_mesh() {
        return Err(ParamError::new(
            "cloth.mesh",
            "a mesh",
            "the scene's cloth is a mesh already (this loads a grid as a mesh)",
        ));
    }
    if c.across != [1.0, 0.0, 0.0] || c.down != [0.0, 0.0, 1.0] || c.pinning != Pinning::TopCorners {
        return Err(ParamError::new(
            "cloth",
            "another orientation or pinning",
            "the grid is loaded as a mesh lying in the xz-plane held at its top corners",
        ));
    }
    let placement = Placement { translate: c.top_center, ..Placement::default() };
    let mut scene = grid.clone();
    scene.cloth.mesh = Some(format!("grid_mesh({})", c.n).into());
    scene.cloth.pinning = Pinning::Vertices(vec![0, c.n - 1]);
    scene.cloth.translate = placement.translate;
    let placed = PlacedMesh::new(&grid_mesh(c.n, c.size), &placement)
        .map_err(|e| ParamError::new("cloth.mesh", "grid_mesh", e.to_string()))?;
    scene.cloth.mesh_data = Some(std::sync::Arc::new(placed));
    Ok(scene)
}

/// The mean and largest distance between the particles of two states of one cloth, m.
pub fn mean_and_max_distance(a: &[crate::grid::V4], b: &[crate::grid::V4]) -> (f32, f32) {
    let d: Vec<f32> = a.iter().zip(b).map(|(p, q)| (0..3).map(|c| (p[c] - q[c]).powi(2)).sum::<f32>().sqrt()).collect();
    (d.iter().sum::<f32>() / d.len().max(1) as f32, d.iter().copied().fold(0.0, f32::max))
}
