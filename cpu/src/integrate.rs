//! `integrate` — per particle: Verlet in velocity form (symplectic Euler),
//! `v' = (1 − damping)·v + f·dt/m`, `x' = x + v'·dt`; pinned particles stay (v = 0), the
//! grabbed particle is put on its target (with the velocity that takes it there), and the
//! floor clamps.
//!
//! The state crosses kernels as (x, v), both f32: the velocity is never a difference of two
//! positions, so gravity's increment `g·dt` is kept at any dt (as `x − x*`, Verlet's two
//! f32 positions round `g·dt²` to a few ulps of x, biasing every integrator that reads
//! a velocity back from them).

use glam::Vec3;

use super::{Exec, dt_over_mass, for_each2, v3, v4};
use clothlab_core::grid::V4;
use clothlab_core::step_params::StepParams;

/// Resolves a contact with a surface of unit normal `nrm` for a particle moving at `v`:
/// the velocity into the surface is removed and the tangential velocity reduced by
/// `friction`; a velocity out of it is kept.
#[inline(always)]
pub(crate) fn contact_vel(v: Vec3, nrm: Vec3, friction: f32) -> Vec3 {
    let vn = v.dot(nrm);
    let vt = v - vn * nrm;
    vt * (1.0 - friction) + vn.max(0.0) * nrm
}

/// [`contact_vel`] against a surface moving at `vs`: the particle's velocity relative to
/// the surface loses its part into it and friction's share of its tangential part (a
/// still surface, `vs` = 0, gives `contact_vel`'s values).
#[inline(always)]
pub(crate) fn contact_vel_moving(v: Vec3, vs: Vec3, nrm: Vec3, friction: f32) -> Vec3 {
    let w = v - vs;
    let vn = w.dot(nrm);
    let vt = w - vn * nrm;
    // (vs + tangential) + normal, added in this order: written vs + (tangential + normal),
    // Mesa reassociates it into this on the GPU (1 ulp off in a third of the contacts).
    vs + vt * (1.0 - friction) + vn.max(0.0) * nrm
}

/// Coulomb friction at a contact (`SimParams::static_friction`, `kinetic_friction`; on
/// when [`StepParams::coulomb`]) for a particle at `x` (already on the surface) moving at
/// `v` against a surface of unit normal `nrm` moving at `vs`: the contact removes the
/// relative velocity into the surface, `Δv_n = max(−v_n, 0)`, the impulse per unit mass
/// that bounds friction's. The tangential relative velocity `v_t` is removed when
/// `|v_t| ≤ μs·Δv_n` (sticking) and shortened by `μk·Δv_n` otherwise (sliding: a particle
/// resting on a floor slows at μk·g). The friction acts over the substep as the normal
/// force does, so the position moves back by the velocity it removed times `dt`: a
/// particle held by static friction on a slope does not creep. The shaders'
/// `coulomb_contact`, in the same order.
#[inline(always)]
pub(crate) fn coulomb_contact(p: &StepParams, x: Vec3, v: Vec3, vs: Vec3, nrm: Vec3) -> (Vec3, Vec3) {
    let w = v - vs;
    let vn = w.dot(nrm);
    let vt = w - vn * nrm;
    let dvn = (-vn).max(0.0);
    let vtl = (vt.x * vt.x + vt.y * vt.y + vt.z * vt.z).sqrt();
    let keep = if vtl > p.mu_static() * dvn { 1.0 - p.mu_kinetic() * dvn / vtl } else { 0.0 };
    let vt2 = vt * keep;
    (x + (vt2 - vt) * p.dt, vs + vt2 + vn.max(0.0) * nrm)
}

/// The contact with a surface of unit normal `nrm` moving at `vs` of a particle pushed to
/// `x` and moving at `v`: [`contact_vel_moving`]'s share of friction, or Coulomb's
/// ([`coulomb_contact`]) where the parameters ask for it. The new `(x, v)`.
#[inline(always)]
pub(crate) fn contact(p: &StepParams, x: Vec3, v: Vec3, vs: Vec3, nrm: Vec3) -> (Vec3, Vec3) {
    if p.coulomb() { coulomb_contact(p, x, v, vs, nrm) } else { (x, contact_vel_moving(v, vs, nrm, p.friction)) }
}

/// The velocity that takes a particle from `x` to `target` in one substep of `dt`.
#[inline(always)]
pub(crate) fn grab_vel(x: Vec3, target: Vec3, dt: f32) -> Vec3 {
    (target - x) * (1.0 / dt)
}

/// Advances every particle by one substep.
pub fn integrate(exec: Exec, p: &StepParams, force: &[V4], pos: &mut [V4], vel: &mut [V4]) {
    for_each2(exec, pos, vel, |i, x4, v4_| integrate_at(i, p, force[i], x4, v4_));
}

/// The substep of particle `i`, in place.
#[inline(always)]
pub(crate) fn integrate_at(i: usize, p: &StepParams, force: V4, x4: &mut V4, vel4: &mut V4) {
    let w = x4[3];
    let x = v3(*x4);
    if i as i32 == p.grab_index {
        *vel4 = v4(grab_vel(x, v3(p.grab_target), p.dt), 0.0);
        *x4 = v4(v3(p.grab_target), w);
        return;
    }
    if w == 0.0 {
        *vel4 = [0.0; 4];
        return;
    }
    let v = v3(*vel4) * (1.0 - p.damping) + v3(force) * dt_over_mass(p, w);
    let (xn, vn) = floor_clamp(p, x + v * p.dt, v);
    *vel4 = v4(vn, 0.0);
    *x4 = v4(xn, w);
}

/// The floor's contact for a particle that moves to `x` with velocity `v`.
#[inline(always)]
pub(crate) fn floor_clamp(p: &StepParams, mut x: Vec3, mut v: Vec3) -> (Vec3, Vec3) {
    let floor = p.floor_y + p.margin;
    if x.y < floor {
        x.y = floor;
        if p.coulomb() {
            (x, v) = coulomb_contact(p, x, v, Vec3::ZERO, Vec3::Y);
        } else {
            v = contact_vel(v, Vec3::Y, p.friction);
        }
    }
    (x, v)
}
