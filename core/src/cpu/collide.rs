//! `collide` — per particle: push particles out of spheres and boxes (inflated by the
//! collision margin) to the nearest surface point; the velocity into the surface is
//! removed and the tangential velocity reduced by friction, both relative to the
//! collider's surface where it moves (`crate::motion`).

use glam::Vec3;

use super::integrate::{contact_vel_moving, integrate_at, surface_vel};
use super::{Exec, for_each2, v3, v4};
use crate::grid::{StepParams, V4};
use crate::scene::{Aabb, Sphere};

/// Resolves every particle against every collider, spheres first, in scene order.
pub fn collide(exec: Exec, p: &StepParams, spheres: &[Sphere], boxes: &[Aabb], pos: &mut [V4], vel: &mut [V4]) {
    let spheres = &spheres[..p.num_spheres as usize];
    let boxes = &boxes[..p.num_boxes as usize];
    for_each2(exec, pos, vel, |i, x4, v4_| collide_at(i, p, spheres, boxes, x4, v4_));
}

/// `integrate` then `collide` for each particle in one sweep (both touch only their own
/// particle, so this is exactly the two kernels run one after the other).
#[allow(clippy::too_many_arguments)]
pub fn integrate_collide(
    exec: Exec,
    p: &StepParams,
    spheres: &[Sphere],
    boxes: &[Aabb],
    force: &[V4],
    pos: &mut [V4],
    vel: &mut [V4],
) {
    let spheres = &spheres[..p.num_spheres as usize];
    let boxes = &boxes[..p.num_boxes as usize];
    for_each2(exec, pos, vel, |i, x4, v4_| {
        integrate_at(i, p, force[i], x4, v4_);
        collide_at(i, p, spheres, boxes, x4, v4_);
    });
}

/// Particle `i` against `spheres` and `boxes` (already cut to their counts), in place.
#[inline(always)]
pub(crate) fn collide_at(i: usize, p: &StepParams, spheres: &[Sphere], boxes: &[Aabb], x4: &mut V4, vel4: &mut V4) {
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
            v = contact_vel_moving(v, vs, nrm, p.friction);
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
            v = contact_vel_moving(v, v3(b.velocity), nrm, p.friction);
        }
    }
    *x4 = v4(x, x4[3]);
    *vel4 = v4(v, 0.0);
}
