//! `forces` — per particle: gravity and linear air drag, added to the wind force that the
//! last `vertex_normals` left in the force buffer.

use glam::Vec3;

use super::{Exec, for_each, mass, v3, v4};
use clothlab_core::grid::V4;
use clothlab_core::step_params::StepParams;

/// `force[i] += mᵢ g - air_drag · mᵢ · v` (mᵢ from `pos[i].w`, see `cpu::mass`).
pub fn forces(exec: Exec, p: &StepParams, pos: &[V4], vel: &[V4], force: &mut [V4]) {
    for_each(exec, force, |i, f| {
        let (g, drag) = forces_consts_w(p, pos[i][3]);
        *f = forces_at(*f, vel[i], g, drag)
    });
}

/// Weight `m g` and the drag factor `air_drag · m` (per m/s) of a particle of the
/// reference mass (every particle of a grid).
#[inline(always)]
pub(crate) fn forces_consts(p: &StepParams) -> (Vec3, f32) {
    (v3(p.gravity) * p.particle_mass, p.air_drag * p.particle_mass)
}

/// [`forces_consts`] for a particle whose position has w = `w`.
#[inline(always)]
pub(crate) fn forces_consts_w(p: &StepParams, w: f32) -> (Vec3, f32) {
    let m = mass(p, w);
    (v3(p.gravity) * m, p.air_drag * m)
}

/// The force of one particle moving at `v`: `f + m g - drag · v`.
#[inline(always)]
pub(crate) fn forces_at(f: V4, v: V4, g: Vec3, drag: f32) -> V4 {
    v4(v3(f) + g - v3(v) * drag, 0.0)
}
