//! What every renderer (wgpu's, Vulkan's, GL's) draws, as plain data: the static scene mesh, the fabric texture, the
//! cloth's line list and the per-frame constants (camera, light) of `shaders/wgsl/render.wgsl`.

use std::collections::BTreeSet;

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};

use crate::grid::ClothTopology;
use crate::scene::Scene;
use crate::solver::View;

/// Shadow-map side, texels.
pub const SHADOW_SIZE: u32 = 2048;
/// MSAA samples of the main pass.
pub const SAMPLES: u32 = 4;
/// Sky colour (linear RGBA), the main pass's clear value.
pub const SKY: [f32; 4] = [0.62, 0.72, 0.85, 1.0];

/// The constants of one frame (`Frame` in render.wgsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct Frame {
    /// Camera view-projection.
    pub view_proj: [[f32; 4]; 4],
    /// Light view-projection (the shadow map's).
    pub light_view_proj: [[f32; 4]; 4],
    /// Light position, w = 1.
    pub light_pos: [f32; 4],
    /// Eye position, w = 1.
    pub eye: [f32; 4],
    /// x shadow-map texel size, y depth bias, z cloth material, w unused.
    pub misc: [f32; 4],
}

impl Frame {
    /// The constants for `view` on a `width × height` target.
    pub fn new(view: &View, width: u32, height: u32) -> Self {
        let aspect = width as f32 / height as f32;
        let light = Vec3::from(view.light);
        let light_target = Vec3::new(0.0, 0.6, 0.0);
        let light_view_proj = Mat4::perspective_rh(70f32.to_radians(), 1.0, 0.5, 30.0)
            * Mat4::look_at_rh(
                light,
                light_target,
                if (light - light_target).cross(Vec3::Y).length() < 1e-3 { Vec3::Z } else { Vec3::Y },
            );
        let eye = view.camera.eye();
        Frame {
            view_proj: view.camera.view_proj(aspect).to_cols_array_2d(),
            light_view_proj: light_view_proj.to_cols_array_2d(),
            light_pos: [light.x, light.y, light.z, 1.0],
            eye: [eye.x, eye.y, eye.z, 1.0],
            misc: [1.0 / SHADOW_SIZE as f32, 0.0004, 3.0, 0.0],
        }
    }
}

/// A vertex of the static mesh: position, normal, uv, material (0 floor, 1 sphere, 2 box).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct StaticVertex {
    /// Position, m.
    pub pos: [f32; 3],
    /// Unit normal.
    pub normal: [f32; 3],
    /// Texture coordinates.
    pub uv: [f32; 2],
    /// Material id.
    pub material: u32,
}

/// The cloth's edges as a line list (each edge of its triangles once).
pub fn cloth_lines(topo: &ClothTopology) -> Vec<u32> {
    let mut edges = BTreeSet::new();
    for t in &topo.triangles {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            edges.insert((a.min(b), a.max(b)));
        }
    }
    edges.iter().flat_map(|&(a, b)| [a, b]).collect()
}

/// A capsule about the segment `a`–`b` of radius `r`: positions, outward normals and
/// triangles counter-clockwise from outside (a hemisphere at each end joined by a tube;
/// `rings` latitude steps per hemisphere, `around` longitude steps).
pub fn capsule_mesh(a: [f32; 3], b: [f32; 3], r: f32, rings: u32, around: u32) -> CapsuleMesh {
    use glam::Vec3;
    let (a, b) = (Vec3::from(a), Vec3::from(b));
    let axis = (b - a).try_normalize().unwrap_or(Vec3::Y);
    let e1 = axis.any_orthonormal_vector();
    let e2 = axis.cross(e1);
    let (mut pos, mut nrm) = (Vec::new(), Vec::new());
    // Latitudes from a's pole (−axis) to b's (+axis): the first hemisphere about a, the
    // second about b.
    for j in 0..=2 * rings + 1 {
        let (centre, th) = if j <= rings {
            (a, std::f32::consts::FRAC_PI_2 * (j as f32 / rings as f32 - 1.0))
        } else {
            (b, std::f32::consts::FRAC_PI_2 * ((j - rings - 1) as f32 / rings as f32))
        };
        for i in 0..around {
            let ph = std::f32::consts::TAU * i as f32 / around as f32;
            let n = axis * th.sin() + (e1 * ph.cos() + e2 * ph.sin()) * th.cos();
            pos.push((centre + n * r).to_array());
            nrm.push(n.to_array());
        }
    }
    let mut tris = Vec::new();
    for j in 0..2 * rings + 1 {
        for i in 0..around {
            let p = j * around + i;
            let q = j * around + (i + 1) % around;
            tris.push([p, q + around, p + around]);
            tris.push([p, q, q + around]);
        }
    }
    (pos, nrm, tris)
}

/// A capped cylinder about the segment `a`–`b` of radius `r`: positions, outward normals
/// and triangles counter-clockwise from outside (a tube of `around` steps with smooth
/// normals, and a flat disc at each end with its own vertices, so the rims stay sharp).
pub fn cylinder_mesh(a: [f32; 3], b: [f32; 3], r: f32, around: u32) -> CapsuleMesh {
    use glam::Vec3;
    let (a, b) = (Vec3::from(a), Vec3::from(b));
    let axis = (b - a).try_normalize().unwrap_or(Vec3::Y);
    let e1 = axis.any_orthonormal_vector();
    let e2 = axis.cross(e1);
    let ring = |i: u32| {
        let ph = std::f32::consts::TAU * i as f32 / around as f32;
        e1 * ph.cos() + e2 * ph.sin()
    };
    let (mut pos, mut nrm, mut tris) = (Vec::new(), Vec::new(), Vec::new());
    // The tube: ring i at a (2i) and at b (2i + 1).
    for i in 0..around {
        let d = ring(i);
        pos.extend([(a + d * r).to_array(), (b + d * r).to_array()]);
        nrm.extend([d.to_array(), d.to_array()]);
    }
    for i in 0..around {
        let (p, q) = (2 * i, 2 * ((i + 1) % around));
        tris.push([p, q, q + 1]);
        tris.push([p, q + 1, p + 1]);
    }
    // The caps: a centre and a rim each, facing −axis at a and +axis at b.
    for (c, n) in [(a, -axis), (b, axis)] {
        let centre = pos.len() as u32;
        pos.push(c.to_array());
        nrm.push(n.to_array());
        for i in 0..around {
            pos.push((c + ring(i) * r).to_array());
            nrm.push(n.to_array());
        }
        for i in 0..around {
            let (p, q) = (centre + 1 + i, centre + 1 + (i + 1) % around);
            tris.push(if n == axis { [centre, p, q] } else { [centre, q, p] });
        }
    }
    (pos, nrm, tris)
}

/// Rod `rod`'s mesh by its kind ([`capsule_mesh`] with `around / 4` rings a hemisphere,
/// [`cylinder_mesh`], [`cone_mesh`]), `around` steps about its axis.
pub fn rod_mesh(rod: &crate::Rod, around: u32) -> CapsuleMesh {
    let at = |p: [f32; 4]| [p[0], p[1], p[2]];
    let (a, b, r) = (at(rod.a), at(rod.b), rod.radius());
    match rod.kind {
        crate::RodKind::Capsule => capsule_mesh(a, b, r, around / 4, around),
        crate::RodKind::Cylinder => cylinder_mesh(a, b, r, around),
        crate::RodKind::Cone => cone_mesh(a, b, r, around),
    }
}

/// A cone, its base the disc of radius `r` about `a` across the axis, its apex at `b`:
/// positions, outward normals and triangles counter-clockwise from outside (the side in
/// `around` steps with smooth normals, the apex once a step with its step's normal, and
/// the base a flat disc with its own vertices, so the rim stays sharp).
pub fn cone_mesh(a: [f32; 3], b: [f32; 3], r: f32, around: u32) -> CapsuleMesh {
    use glam::Vec3;
    let (a, b) = (Vec3::from(a), Vec3::from(b));
    let len = (b - a).length();
    let axis = (b - a).try_normalize().unwrap_or(Vec3::Y);
    let e1 = axis.any_orthonormal_vector();
    let e2 = axis.cross(e1);
    let ring = |ph: f32| e1 * ph.cos() + e2 * ph.sin();
    let step = std::f32::consts::TAU / around as f32;
    // The side's normal where the ring points along `d`: out and up the slope.
    let slope = |d: Vec3| (d * len + axis * r).normalize_or(axis);
    let (mut pos, mut nrm, mut tris) = (Vec::new(), Vec::new(), Vec::new());
    // The side: rim vertex i at 2i, step i's apex at 2i + 1.
    for i in 0..around {
        let (d, half) = (ring(step * i as f32), ring(step * (i as f32 + 0.5)));
        pos.extend([(a + d * r).to_array(), b.to_array()]);
        nrm.extend([slope(d).to_array(), slope(half).to_array()]);
    }
    for i in 0..around {
        tris.push([2 * i, 2 * ((i + 1) % around), 2 * i + 1]);
    }
    // The base: a centre and a rim facing −axis.
    let centre = pos.len() as u32;
    pos.push(a.to_array());
    nrm.push((-axis).to_array());
    for i in 0..around {
        pos.push((a + ring(step * i as f32) * r).to_array());
        nrm.push((-axis).to_array());
    }
    for i in 0..around {
        tris.push([centre, centre + 1 + (i + 1) % around, centre + 1 + i]);
    }
    (pos, nrm, tris)
}

/// [`capsule_mesh`]'s positions, normals and triangles.
pub type CapsuleMesh = (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<[u32; 3]>);

/// Floor, spheres, boxes, capsules, cylinders and bodies as one triangle list (never empty). A body is drawn
/// as its mesh with smooth normals (area-weighted), where [`Scene::moved_to`] put it.
pub fn static_mesh(scene: &Scene) -> (Vec<StaticVertex>, Vec<u32>) {
    let mut v = Vec::new();
    let mut idx = Vec::new();
    let mut quad = |v: &mut Vec<StaticVertex>, corners: [[f32; 3]; 4], normal: [f32; 3], material: u32| {
        let base = v.len() as u32;
        for (k, c) in corners.iter().enumerate() {
            let uv = [(k == 1 || k == 2) as u32 as f32, (k >= 2) as u32 as f32];
            v.push(StaticVertex { pos: *c, normal, uv, material });
        }
        idx.extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
    };
    if let Some(y) = scene.floor_y {
        let s = 6.0;
        quad(&mut v, [[-s, y, -s], [-s, y, s], [s, y, s], [s, y, -s]], [0.0, 1.0, 0.0], 0);
    }
    for b in &scene.boxes {
        let (lo, hi) = (b.min, b.max);
        let faces: [([[f32; 3]; 4], [f32; 3]); 6] = [
            (
                [[lo[0], hi[1], lo[2]], [lo[0], hi[1], hi[2]], [hi[0], hi[1], hi[2]], [hi[0], hi[1], lo[2]]],
                [0.0, 1.0, 0.0],
            ),
            (
                [[lo[0], lo[1], lo[2]], [hi[0], lo[1], lo[2]], [hi[0], lo[1], hi[2]], [lo[0], lo[1], hi[2]]],
                [0.0, -1.0, 0.0],
            ),
            (
                [[lo[0], lo[1], hi[2]], [hi[0], lo[1], hi[2]], [hi[0], hi[1], hi[2]], [lo[0], hi[1], hi[2]]],
                [0.0, 0.0, 1.0],
            ),
            (
                [[lo[0], lo[1], lo[2]], [lo[0], hi[1], lo[2]], [hi[0], hi[1], lo[2]], [hi[0], lo[1], lo[2]]],
                [0.0, 0.0, -1.0],
            ),
            (
                [[hi[0], lo[1], lo[2]], [hi[0], hi[1], lo[2]], [hi[0], hi[1], hi[2]], [hi[0], lo[1], hi[2]]],
                [1.0, 0.0, 0.0],
            ),
            (
                [[lo[0], lo[1], lo[2]], [lo[0], lo[1], hi[2]], [lo[0], hi[1], hi[2]], [lo[0], hi[1], lo[2]]],
                [-1.0, 0.0, 0.0],
            ),
        ];
        for (c, nrm) in faces {
            quad(&mut v, c, nrm, 2);
        }
    }
    let (rings, segs) = (24u32, 48u32);
    for sp in &scene.spheres {
        let base = v.len() as u32;
        for r in 0..=rings {
            let th = std::f32::consts::PI * r as f32 / rings as f32;
            for sgi in 0..=segs {
                let ph = std::f32::consts::TAU * sgi as f32 / segs as f32;
                let nrm = [th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()];
                let pos = [
                    sp.center[0] + sp.radius * nrm[0],
                    sp.center[1] + sp.radius * nrm[1],
                    sp.center[2] + sp.radius * nrm[2],
                ];
                v.push(StaticVertex { pos, normal: nrm, uv: [0.0, 0.0], material: 1 });
            }
        }
        for r in 0..rings {
            for sgi in 0..segs {
                let a = base + r * (segs + 1) + sgi;
                let b = a + segs + 1;
                idx.extend_from_slice(&[a, a + 1, b, a + 1, b + 1, b]);
            }
        }
    }
    for (p, n, t) in scene.rods.iter().map(|r| rod_mesh(r, 48)) {
        let base = v.len() as u32;
        for (pos, normal) in p.into_iter().zip(n) {
            v.push(StaticVertex { pos, normal, uv: [0.0, 0.0], material: 1 });
        }
        idx.extend(t.iter().flatten().map(|&k| base + k));
    }
    for body in &scene.bodies {
        let m = &body.mesh;
        let base = v.len() as u32;
        let mut normals = vec![glam::Vec3::ZERO; m.positions.len()];
        for t in &m.triangles {
            let [a, b, c] = t.map(|k| glam::Vec3::from(m.positions[k as usize]));
            let n = (b - a).cross(c - a);
            for &k in t {
                normals[k as usize] += n;
            }
        }
        for (p, n) in m.positions.iter().zip(&normals) {
            let normal = n.normalize_or(glam::Vec3::Y).to_array();
            v.push(StaticVertex { pos: *p, normal, uv: [0.0, 0.0], material: 1 });
        }
        idx.extend(m.triangles.iter().flatten().map(|&k| base + k));
    }
    if idx.is_empty() {
        // Nothing but the cloth (no floor, no colliders): one degenerate triangle, so that
        // every renderer still has a buffer to bind (Vulkan has no empty buffers).
        v.push(StaticVertex { pos: [0.0; 3], normal: [0.0, 1.0, 0.0], uv: [0.0; 2], material: 0 });
        idx.extend_from_slice(&[0, 0, 0]);
    }
    (v, idx)
}

/// A woven-looking fabric texture (64 × 64 sRGB RGBA8): two thread directions with a slight irregularity.
pub fn fabric_texture() -> Vec<u8> {
    let size = 64usize;
    let mut px = Vec::with_capacity(size * size * 4);
    for y in 0..size {
        for x in 0..size {
            let warp = ((x / 4 + y / 8) % 2 == 0) as u8 as f32;
            let thread = 0.5 + 0.5 * (((x % 4) as f32 - 1.5).abs() / 1.5);
            let noise = ((x * 7 + y * 13) % 11) as f32 / 11.0 * 0.06;
            let k = 0.78 + 0.12 * warp * thread - noise;
            let (r, g, b) = (0.32 * k, 0.5 * k, 0.78 * k);
            px.extend_from_slice(&[(r * 255.0) as u8, (g * 255.0) as u8, (b * 255.0) as u8, 255]);
        }
    }
    px
}

#[cfg(test)]
mod capsule_tests {
    #[test]
    fn a_capsule_mesh_lies_on_its_surface_and_faces_out() {
        // Every vertex at the radius from the axis segment (to rounding, 1e-6 m), every
        // triangle's normal outward (its centroid moved along it leaves the capsule), and
        // it is closed (every edge in two triangles).
        let (a, b, r) = ([0.1, 0.2, 0.3], [0.9, -0.4, 0.5], 0.15);
        let (pos, nrm, tris) = super::capsule_mesh(a, b, r, 6, 16);
        let (va, vb) = (glam::Vec3::from(a), glam::Vec3::from(b));
        let dist = |p: glam::Vec3| {
            let ab = vb - va;
            let s = ((p - va).dot(ab) / ab.dot(ab)).clamp(0.0, 1.0);
            (p - (va + ab * s)).length()
        };
        for (p, n) in pos.iter().zip(&nrm) {
            assert!((dist(glam::Vec3::from(*p)) - r).abs() < 1e-6, "{p:?}");
            assert!((glam::Vec3::from(*n).length() - 1.0).abs() < 1e-5);
        }
        let mut outward = 0;
        for t in &tris {
            let [p0, p1, p2] = t.map(|k| glam::Vec3::from(pos[k as usize]));
            let n = (p1 - p0).cross(p2 - p0);
            if n.length() < 1e-9 {
                continue; // a pole's sliver
            }
            let c = (p0 + p1 + p2) / 3.0;
            if dist(c + n.normalize() * 0.01) > dist(c) {
                outward += 1;
            } else {
                panic!("triangle {t:?} faces in");
            }
        }
        assert!(outward >= tris.len() - 2 * 16, "{outward} of {} outward", tris.len());
    }

    #[test]
    fn cylinder_and_cone_meshes_are_closed_lie_on_their_surfaces_and_face_out() {
        use crate::contact::Shape;
        // Every triangle's centroid moved 4 mm out along its normal leaves the shape
        // (no contact: a chord of 16 steps about r = 0.15 m lies 2.9 mm inside) and 4 mm in is
        // inside (a contact): the mesh is the surface the
        // contact pushes to, drawn the right way round; every edge is in two triangles.
        for kind in [crate::RodKind::Cylinder, crate::RodKind::Cone] {
            let (a, b, r) = ([0.1, 0.2, 0.3], [0.9, -0.4, 0.5], 0.15);
            let rod = crate::Rod::new(kind, a, b, r);
            let (pos, nrm, tris) = super::rod_mesh(&rod, 16);
            assert_eq!(pos.len(), nrm.len());
            for t in &tris {
                let [p0, p1, p2] = t.map(|k| glam::Vec3::from(pos[k as usize]));
                let n = (p1 - p0).cross(p2 - p0).normalize();
                let c = (p0 + p1 + p2) / 3.0;
                assert!(rod.contact(c + n * 4e-3, 0.0).is_none(), "{kind:?}: triangle {t:?} faces in");
                assert!(rod.contact(c - n * 4e-3, 0.0).is_some(), "{kind:?}: triangle {t:?} off the surface");
            }
            // Each vertex's normal within 12° of its triangles' (the apex's: its step's).
            for t in &tris {
                let [p0, p1, p2] = t.map(|k| glam::Vec3::from(pos[k as usize]));
                let n = (p1 - p0).cross(p2 - p0).normalize();
                for &k in t {
                    let v = glam::Vec3::from(nrm[k as usize]);
                    assert!(v.dot(n) > 12f32.to_radians().cos(), "{kind:?}: vertex {k}'s normal {v} against {n}");
                }
            }
            closed(&pos, &tris);
        }
    }

    /// Every edge of `tris` is in two triangles (vertices at one place are one).
    fn closed(pos: &[[f32; 3]], tris: &[[u32; 3]]) {
        let mut edges = std::collections::HashMap::new();
        for t in tris {
            for k in 0..3 {
                let (p, q) = (pos[t[k] as usize], pos[t[(k + 1) % 3] as usize]);
                let key = |v: [f32; 3]| v.map(|c| (c * 1e5).round() as i64);
                let (p, q) = (key(p), key(q));
                *edges.entry(if p < q { (p, q) } else { (q, p) }).or_insert(0) += 1;
            }
        }
        assert!(edges.values().all(|&c| c == 2), "open edges: {:?}", edges.values().filter(|&&c| c != 2).count());
    }
}
