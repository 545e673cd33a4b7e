//! `forces` — per particle: gravity and linear air drag, added to the wind force that the
//! last `vertex_normals` left in the force buffer.

use super::{Exec, for_each, v3, v4};
use crate::grid::{StepParams, V4};

/// `force[i] += m g - air_drag · m · v`, with `v = (pos - prev) / dt`.
pub fn forces(exec: Exec, p: &StepParams, pos: &[V4], prev: &[V4], force: &mut [V4]) {
    let g = v3(p.gravity) * p.particle_mass;
    let drag = p.air_drag * p.particle_mass / p.dt;
    for_each(exec, force, |i, f| {
        let v_dt = v3(pos[i]) - v3(prev[i]);
        *f = v4(v3(*f) + g - v_dt * drag, 0.0);
    });
}
