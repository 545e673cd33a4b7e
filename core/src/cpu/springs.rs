//! `springs` — the spring force of thesis eq. 4.35 with spring damping:
//! `F_a = -[ks (|L| - r) + kd (L'·L)/|L|] L/|L|`, `L = x_a - x_b`, `L' = v_a - v_b`.

use glam::Vec3;

use super::{Exec, for_each, v3, v4};
use crate::grid::{SLOTS, Spring, SpringSlot, V4};

/// Force on end `a` of a spring with `l = x_a - x_b` and `dv = (v_a - v_b)·dt`.
#[inline(always)]
fn spring_force(l: Vec3, dv: Vec3, s: &SpringSlot, inv_dt: f32) -> Vec3 {
    let len = l.length();
    if len <= f32::MIN_POSITIVE {
        return Vec3::ZERO;
    }
    let dir = l / len;
    -(s.ks * (len - s.rest) + s.kd * inv_dt * dv.dot(dir)) * dir
}

/// Gather (optimized kernels, CPU solvers): each particle adds its 12 slots in slot order.
pub fn springs(exec: Exec, dt: f32, slots: &[SpringSlot], pos: &[V4], prev: &[V4], force: &mut [V4]) {
    let inv_dt = 1.0 / dt;
    for_each(exec, force, |i, f| {
        let xa = v3(pos[i]);
        let va = xa - v3(prev[i]);
        let mut acc = v3(*f);
        for s in &slots[i * SLOTS..(i + 1) * SLOTS] {
            if s.neighbor < 0 {
                continue;
            }
            let b = s.neighbor as usize;
            let xb = v3(pos[b]);
            let vb = xb - v3(prev[b]);
            acc += spring_force(xa - xb, va - vb, s, inv_dt);
        }
        *f = v4(acc, 0.0);
    });
}

/// Scatter (twin of the naive kernel): each spring adds its force to both ends. The
/// summation order differs from [`springs`], so results agree only up to rounding.
pub fn springs_scatter(dt: f32, springs: &[Spring], pos: &[V4], prev: &[V4], force: &mut [V4]) {
    let inv_dt = 1.0 / dt;
    for s in springs {
        let (a, b) = (s.a as usize, s.b as usize);
        let (xa, xb) = (v3(pos[a]), v3(pos[b]));
        let (va, vb) = (xa - v3(prev[a]), xb - v3(prev[b]));
        let slot = SpringSlot { neighbor: s.b as i32, rest: s.rest, ks: s.ks, kd: s.kd };
        let fa = spring_force(xa - xb, va - vb, &slot, inv_dt);
        force[a] = v4(v3(force[a]) + fa, 0.0);
        force[b] = v4(v3(force[b]) - fa, 0.0);
    }
}
