//! `collide` — per particle: push particles out of spheres, boxes, rods (capsules, cylinders) and
//! bodies (grown by the collision margin) to the nearest surface point
//! ([`clothlab_core::contact`]: a body's along its field's gradient, `clothlab_core::sdf`); the velocity
//! into the surface is removed and the tangential velocity reduced by friction, both
//! relative to the collider's surface where it moves (`clothlab_core::motion`).

use glam::Vec3;

use super::integrate::{contact, integrate_at};
use super::{Exec, for_each2, v3, v4};
use clothlab_core::contact::{Body, Contact, Shape};
use clothlab_core::grid::V4;
use clothlab_core::scene::{Aabb, Rod, Sphere};
use clothlab_core::sdf::{Bodies, SdfHead};
use clothlab_core::step_params::StepParams;

/// What the particles collide with (besides the floor): the spheres, boxes, rods
/// (capsules, cylinders) and bodies at the current substep.
#[derive(Debug, Clone, Copy, Default)]
pub struct Colliders<'a> {
    /// Spheres.
    pub spheres: &'a [Sphere],
    /// Boxes.
    pub boxes: &'a [Aabb],
    /// Rods.
    pub rods: &'a [Rod],
    /// Bodies (mesh colliders).
    pub bodies: Bodies<'a>,
}

impl<'a> Colliders<'a> {
    /// Spheres and boxes, no rods or bodies.
    pub fn new(spheres: &'a [Sphere], boxes: &'a [Aabb]) -> Self {
        Self { spheres, boxes, rods: &[], bodies: Bodies::default() }
    }

    /// Cut to the counts in `p` (what the kernels loop over).
    #[inline(always)]
    pub fn cut(self, p: &StepParams) -> Self {
        let heads = self.bodies.heads;
        Self {
            spheres: &self.spheres[..(p.num_spheres as usize).min(self.spheres.len())],
            boxes: &self.boxes[..(p.num_boxes as usize).min(self.boxes.len())],
            rods: &self.rods[..(p.num_rods as usize).min(self.rods.len())],
            bodies: Bodies { heads: &heads[..(p.num_bodies as usize).min(heads.len())], values: self.bodies.values },
        }
    }

    /// Every collider's contact with a point at `x`, in scene order (spheres, boxes,
    /// rods, bodies), each shape grown by `reach`: `touch(x, contact)` may
    /// move `x` before the next shape is tested (`collide` moves it to the contact's
    /// point; VBD's contact energies leave it).
    #[inline(always)]
    pub fn walk(&self, x: &mut Vec3, reach: f32, mut touch: impl FnMut(&mut Vec3, Contact)) {
        fn each<S: Shape>(
            shapes: impl Iterator<Item = S>,
            x: &mut Vec3,
            reach: f32,
            touch: &mut impl FnMut(&mut Vec3, Contact),
        ) {
            for s in shapes {
                if let Some(hit) = s.contact(*x, reach) {
                    touch(x, hit);
                }
            }
        }
        each(self.spheres.iter().copied(), x, reach, &mut touch);
        each(self.boxes.iter().copied(), x, reach, &mut touch);
        each(self.rods.iter().copied(), x, reach, &mut touch);
        each(self.bodies(), x, reach, &mut touch);
    }

    /// The bodies, each with the values.
    pub fn bodies(&self) -> impl Iterator<Item = Body<'a>> + use<'a> {
        let values = self.bodies.values;
        self.bodies.heads.iter().map(move |head| Body { head, values })
    }
}

/// The colliders of a scene at one time, owned: what [`Colliders`] views.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ColliderSet {
    /// Spheres, moved.
    pub spheres: Vec<Sphere>,
    /// Boxes, moved.
    pub boxes: Vec<Aabb>,
    /// Rods, moved.
    pub rods: Vec<Rod>,
    /// The bodies' heads.
    pub heads: Vec<SdfHead>,
    /// The bodies' values (`clothlab_core::sdf::concat`; fixed).
    pub values: Vec<f32>,
}

impl ColliderSet {
    /// `scene`'s colliders at time 0.
    pub fn new(scene: &clothlab_core::Scene) -> Self {
        let mut s = Self { values: clothlab_core::sdf::concat(&scene.bodies).0, ..Self::default() };
        s.move_to(scene, 0.0);
        s
    }

    /// Puts them where `scene`'s motions have them at time `t`, s.
    pub fn move_to(&mut self, scene: &clothlab_core::Scene, t: f64) {
        scene.colliders_at(t, &mut self.spheres, &mut self.boxes);
        scene.rods_at(t, &mut self.rods);
        scene.bodies_at(t, &mut self.heads);
    }

    /// A view of them.
    pub fn view(&self) -> Colliders<'_> {
        Colliders {
            spheres: &self.spheres,
            boxes: &self.boxes,
            rods: &self.rods,
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
    if x4[3] == 0.0 || i as i32 == p.grab_index {
        return;
    }
    let mut x = v3(*x4);
    let mut v = v3(*vel4);
    c.walk(&mut x, p.margin, |x, hit| (*x, v) = contact(p, hit.at, v, hit.vs, hit.n));
    *x4 = v4(x, x4[3]);
    *vel4 = v4(v, 0.0);
}
