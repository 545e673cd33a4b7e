//! `integrate` — per particle: Verlet `x' = x + (1 - damping)(x - x*) + a dt²`; pinned
//! particles stay, the grabbed particle is put on its target, and the floor clamps.

use glam::Vec3;

use super::{Exec, for_each2, v3, v4};
use crate::grid::{StepParams, V4};

/// Resolves a contact with a surface of unit normal `nrm` on which `x` has just been put:
/// the motion into the surface is removed and the tangential motion reduced by `friction`.
/// Returns the new previous position (Verlet's velocity is `x - prev`).
#[inline(always)]
pub(crate) fn contact_prev(x: Vec3, prev: Vec3, nrm: Vec3, friction: f32) -> Vec3 {
    let v = x - prev;
    let vn = v.dot(nrm);
    let vt = v - vn * nrm;
    let v_new = vt * (1.0 - friction) + vn.max(0.0) * nrm;
    x - v_new
}

/// Advances every particle by one substep.
pub fn integrate(exec: Exec, p: &StepParams, force: &[V4], pos: &mut [V4], prev: &mut [V4]) {
    for_each2(exec, pos, prev, |i, x4, xp4| integrate_at(i, p, force[i], x4, xp4));
}

/// The substep of particle `i`, in place.
#[inline(always)]
pub(crate) fn integrate_at(i: usize, p: &StepParams, force: V4, x4: &mut V4, xp4: &mut V4) {
    let w = x4[3];
    let x = v3(*x4);
    if i as i32 == p.grab_index {
        *xp4 = v4(x, 0.0);
        *x4 = v4(v3(p.grab_target), w);
        return;
    }
    if w == 0.0 {
        *xp4 = v4(x, 0.0);
        return;
    }
    let mut xn = x + (x - v3(*xp4)) * (1.0 - p.damping) + v3(force) * (p.dt * p.dt / p.particle_mass);
    let mut xp = x;
    let floor = p.floor_y + p.margin;
    if xn.y < floor {
        xn.y = floor;
        xp = contact_prev(xn, xp, Vec3::Y, p.friction);
    }
    *xp4 = v4(xp, 0.0);
    *x4 = v4(xn, w);
}
