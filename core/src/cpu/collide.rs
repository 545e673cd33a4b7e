//! `collide` — per particle: push particles out of spheres, boxes, capsules and bodies
//! (inflated by the collision margin) to the nearest surface point (a body's: along its
//! field's gradient, `crate::sdf`); the velocity into the surface is removed and the tangential
//! velocity reduced by friction, both relative to the collider's surface where it moves
//! (`crate::motion`).

use glam::Vec3;

use super::integrate::{contact, integrate_at, surface_vel};
use super::{Exec, for_each2, v3, v4};
use crate::grid::V4;
use crate::scene::{Aabb, Capsule, Sphere};
use crate::sdf::{Bodies, SdfHead, sample_grid};
use crate::step_params::StepParams;

/// What the particles collide with (besides the floor): the spheres, boxes, capsules and
/// bodies at the current substep.
#[derive(Debug, Clone, Copy, Default)]
pub struct Colliders<'a> {
    /// Spheres.
    pub spheres: &'a [Sphere],
    /// Boxes.
    pub boxes: &'a [Aabb],
    /// Capsules.
    pub capsules: &'a [Capsule],
    /// Bodies (mesh colliders).
    pub bodies: Bodies<'a>,
}

impl<'a> Colliders<'a> {
    /// Spheres and boxes, no capsules or bodies.
    pub fn new(spheres: &'a [Sphere], boxes: &'a [Aabb]) -> Self {
        Self { spheres, boxes, capsules: &[], bodies: Bodies::default() }
    }

    /// Cut to the counts in `p` (what the kernels loop over).
    #[inline(always)]
    pub fn cut(self, p: &StepParams) -> Self {
        let heads = self.bodies.heads;
        Self {
            spheres: &self.spheres[..(p.num_spheres as usize).min(self.spheres.len())],
            boxes: &self.boxes[..(p.num_boxes as usize).min(self.boxes.len())],
            capsules: &self.capsules[..(p.num_capsules as usize).min(self.capsules.len())],
            bodies: Bodies { heads: &heads[..(p.num_bodies as usize).min(heads.len())], values: self.bodies.values },
        }
    }
}

/// The colliders of a scene at one time, owned: what [`Colliders`] views.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ColliderSet {
    /// Spheres, moved.
    pub spheres: Vec<Sphere>,
    /// Boxes, moved.
    pub boxes: Vec<Aabb>,
    /// Capsules, moved.
    pub capsules: Vec<Capsule>,
    /// The bodies' heads.
    pub heads: Vec<SdfHead>,
    /// The bodies' values (`crate::sdf::concat`; fixed).
    pub values: Vec<f32>,
}

impl ColliderSet {
    /// `scene`'s colliders at time 0.
    pub fn new(scene: &crate::Scene) -> Self {
        let mut s = Self { values: crate::sdf::concat(&scene.bodies).0, ..Self::default() };
        s.move_to(scene, 0.0);
        s
    }

    /// Puts them where `scene`'s motions have them at time `t`, s.
    pub fn move_to(&mut self, scene: &crate::Scene, t: f64) {
        scene.colliders_at(t, &mut self.spheres, &mut self.boxes);
        scene.capsules_at(t, &mut self.capsules);
        scene.bodies_at(t, &mut self.heads);
    }

    /// A view of them.
    pub fn view(&self) -> Colliders<'_> {
        Colliders {
            spheres: &self.spheres,
            boxes: &self.boxes,
            capsules: &self.capsules,
            bodies: Bodies { heads: &self.heads, values: &self.values },
        }
    }
}

/// Resolves every particle against every collider, spheres first, in scene order.
pub fn collide(exec: Exec, p: &StepParams, c: Colliders<'_>, pos: &mut [V4], vel: &mut [V4]) {
    let c = c.cut(p);
    for_each2(exec, pos, vel, |i, x4, v4_| collide_at(i, p, c, x4, v4_));
}

/// `integrate` then `collide` for each particle in one sweep (both touch only their own
/// particle, so this is exactly the two kernels run one after the other).
pub fn integrate_collide(exec: Exec, p: &StepParams, c: Colliders<'_>, force: &[V4], pos: &mut [V4], vel: &mut [V4]) {
    let c = c.cut(p);
    for_each2(exec, pos, vel, |i, x4, v4_| {
        integrate_at(i, p, force[i], x4, v4_);
        collide_at(i, p, c, x4, v4_);
    });
}

/// Particle `i` against the colliders `c` (already cut to their counts), in place.
#[inline(always)]
pub(crate) fn collide_at(i: usize, p: &StepParams, c: Colliders<'_>, x4: &mut V4, vel4: &mut V4) {
    let (spheres, boxes) = (c.spheres, c.boxes);
    if x4[3] == 0.0 || i as i32 == p.grab_index {
        return;
    }
    let mut x = v3(*x4);
    let mut v = v3(*vel4);
    for s in spheres {
        let c = Vec3::from(s.center);
        let r = s.radius + p.margin;
        let d = x - c;
        let dist2 = d.length_squared();
        if dist2 < r * r {
            let dist = dist2.sqrt();
            // A particle exactly at the centre is pushed up.
            let nrm = if dist > 1e-12 { d / dist } else { Vec3::Y };
            let arm = nrm * r;
            x = c + arm;
            // The surface's velocity at the contact: the centre's and the spin's.
            let vs = surface_vel(v3(s.velocity), v3(s.spin), arm);
            (x, v) = contact(p, x, v, vs, nrm);
        }
    }
    for b in boxes {
        let lo = v3(b.min) - Vec3::splat(p.margin);
        let hi = v3(b.max) + Vec3::splat(p.margin);
        if x.cmpgt(lo).all() && x.cmplt(hi).all() {
            // Leave through the nearest face.
            let below = x - lo;
            let above = hi - x;
            let mut best = below.x;
            let mut nrm = -Vec3::X;
            let mut face = lo.x;
            let cands = [
                (above.x, Vec3::X, hi.x),
                (below.y, -Vec3::Y, lo.y),
                (above.y, Vec3::Y, hi.y),
                (below.z, -Vec3::Z, lo.z),
                (above.z, Vec3::Z, hi.z),
            ];
            for (dpen, nn, f) in cands {
                if dpen < best {
                    best = dpen;
                    nrm = nn;
                    face = f;
                }
            }
            let axis = nrm.abs();
            x = x * (Vec3::ONE - axis) + axis * face;
            (x, v) = contact(p, x, v, v3(b.velocity), nrm);
        }
    }
    for cap in c.capsules {
        let r = cap.a[3] + p.margin;
        let d = x - capsule_axis_point(cap, x);
        let dist2 = dot3(d, d);
        if dist2 < r * r {
            let dist = dist2.sqrt();
            // A particle on the axis is pushed up.
            let nrm = if dist > 1e-12 { d / dist } else { Vec3::Y };
            x = capsule_axis_point(cap, x) + nrm * r;
            let vs = surface_vel(v3(cap.velocity), v3(cap.spin), x - capsule_center(cap));
            (x, v) = contact(p, x, v, vs, nrm);
        }
    }
    for hd in c.bodies.heads {
        if let Some((phi, nrm)) = body_sample(hd, c.bodies.values, x, p.margin)
            && phi < p.margin
        {
            x += nrm * (p.margin - phi);
            let vs = surface_vel(v3(hd.velocity), v3(hd.spin), x - v3(hd.translation));
            (x, v) = contact(p, x, v, vs, nrm);
        }
    }
    *x4 = v4(x, x4[3]);
    *vel4 = v4(v, 0.0);
}

/// `a·b` summed left to right (the WGSL's `dot3`).
#[inline(always)]
fn dot3(a: Vec3, b: Vec3) -> f32 {
    a.x * b.x + a.y * b.y + a.z * b.z
}

/// Body `hd`'s field at world `x`: `(φ, n̂)` with `n̂` the world direction of its gradient
/// (up where it vanishes), or `None` outside its grid or where φ is surely ≥ `reach`.
/// The WGSL's `body_sample`.
#[inline(always)]
pub(crate) fn body_sample(hd: &SdfHead, values: &[f32], x: Vec3, reach: f32) -> Option<(f32, Vec3)> {
    let (c0, c1, c2) = (v3(hd.cols[0]), v3(hd.cols[1]), v3(hd.cols[2]));
    let d = x - v3(hd.translation);
    let q = [dot3(c0, d), dot3(c1, d), dot3(c2, d)];
    let [nx, ny, nz, first] = hd.dims;
    let (phi, g) = sample_grid(&hd.lo, [nx, ny, nz], values.get(first as usize..)?, q, reach)?;
    let g = Vec3::from(g);
    let gl = dot3(g, g).sqrt();
    let nl = if gl > 1e-12 { g / gl } else { Vec3::Y };
    Some((phi, c0 * nl.x + c1 * nl.y + c2 * nl.z))
}

/// The point of capsule `c`'s axis nearest `x` (the WGSL's `capsule_axis_point`).
#[inline(always)]
pub(crate) fn capsule_axis_point(c: &Capsule, x: Vec3) -> Vec3 {
    let (a, b) = (v3(c.a), v3(c.b));
    let ab = b - a;
    let len2 = dot3(ab, ab);
    let s = if len2 > 1e-24 { (dot3(x - a, ab) / len2).clamp(0.0, 1.0) } else { 0.0 };
    a + ab * s
}

/// Capsule `c`'s centre, `(a + b)·½` (the WGSL's `capsule_center`).
#[inline(always)]
pub(crate) fn capsule_center(c: &Capsule) -> Vec3 {
    (v3(c.a) + v3(c.b)) * 0.5
}
