//! `strain_limit` — one Jacobi pass of Provot's "dynamic inverse" constraint: every
//! structural and shear spring longer than `(1 + τ) · rest` pulls its ends together.
//!
//! Each particle gathers the corrections of its over-stretched springs (slots
//! `0 .. STRAIN_SLOTS`), shared by mobility: a spring to a pinned or grabbed particle moves
//! only the free end, by the whole excess; a spring between two free particles moves each
//! end by half of it. The corrections are averaged over the violated springs (Macklin et
//! al. 2014, "Unified particle physics", §4.2), which keeps a particle pulled by several
//! springs from overshooting. A lone over-stretched spring ends within its bound after
//! one pass. Over-relaxing the average (×1.5) converged faster in the tests but made the
//! particles next to the pins jitter at 1 m/s in a hanging cloth, so there is none.
//!
//! After the springs, the pass applies the particle's tethers (long-range attachments,
//! Kim, Chentanez & Müller 2012): a particle farther than `(1 + τ)` times its rest
//! distance from a pin is put back on that sphere. Jacobi passes move a correction only
//! one spring per pass, so without tethers a cloth hung from two corners stretches without
//! bound as n grows (measured: max structural strain 1.5 at n = 128 and 9.4 at n = 256
//! with 2 passes per substep); with them the pins hold every particle directly.

use super::{Exec, for_each, v3, v4};
use crate::grid::{SLOTS, STRAIN_SLOTS, SpringSlot, StepParams, TETHER_SLOTS, Tether, V4};

/// A spring over `(1 + τ)·rest` is pulled towards `(1 + STRAIN_AIM·τ)·rest`, a little
/// inside the limit: corrections proportional to the excess over the limit itself make
/// Jacobi approach the bound only asymptotically (measured: 0.1002 after 400 passes for
/// τ = 0.1), aiming inside ends the passes in finitely many steps. Aiming far inside
/// (0.9) injects velocity: springs that carry the cloth's weight are pulled in every
/// substep and the pinned corners jitter; 0.95 measured no jitter (max speed of a cloth
/// at rest 0.09 m/s vs 1.1 m/s at 0.9).
pub const STRAIN_AIM: f32 = 0.95;

/// One pass: reads `pos`, writes the corrected positions to `out` (same length).
pub fn strain_limit(
    exec: Exec,
    p: &StepParams,
    slots: &[SpringSlot],
    tethers: &[[Tether; TETHER_SLOTS]],
    pos: &[V4],
    out: &mut [V4],
) {
    let stretch = 1.0 + p.strain_limit;
    let aim = 1.0 + STRAIN_AIM * p.strain_limit;
    let mobility = |k: usize| if k as i32 == p.grab_index { 0.0 } else { pos[k][3] };
    for_each(exec, out, |i, o| {
        let xi = v3(pos[i]);
        let wi = mobility(i);
        if wi == 0.0 {
            *o = pos[i];
            return;
        }
        let mut corr = glam::Vec3::ZERO;
        let mut count = 0.0f32;
        for s in &slots[i * SLOTS..i * SLOTS + STRAIN_SLOTS] {
            if s.neighbor < 0 {
                continue;
            }
            let b = s.neighbor as usize;
            let d = v3(pos[b]) - xi;
            let len = d.length();
            if len > stretch * s.rest {
                let wb = mobility(b);
                let share = wi / (wi + wb);
                corr += d * (share * (len - aim * s.rest) / len);
                count += 1.0;
            }
        }
        let mut x = if count > 0.0 { xi + corr / count } else { xi };
        for t in &tethers[i] {
            if t.pin < 0 {
                continue;
            }
            let pin = v3(pos[t.pin as usize]);
            let d = x - pin;
            let len = d.length();
            let max = stretch * t.rest;
            if len > max {
                x = pin + d * (max / len);
            }
        }
        *o = v4(x, pos[i][3]);
    });
}
