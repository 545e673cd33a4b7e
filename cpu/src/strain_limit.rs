//! `strain_limit` — one Jacobi pass of Provot's "dynamic inverse" constraint: every
//! structural and shear spring longer than `(1 + τ) · rest` pulls its ends together.
//!
//! Each particle gathers the corrections of its over-stretched springs (slots
//! `0 .. STRAIN_SLOTS`), shared by mobility: a spring to a pinned or grabbed particle moves
//! only the free end, by the whole excess; a spring between two free particles moves each
//! end by half of it. Each spring's correction is divided by the larger of its two ends'
//! counts of over-stretched springs ([`strain_count`], a pass of its own before each
//! correction pass): the same number at both ends, so a spring moves its ends by equal and
//! opposite amounts (mass-weighted) and the pass keeps the cloth's momentum, and no
//! particle overshoots — the divisors of its springs are each at least its own count, so
//! its corrections add up to at most their average (Macklin et al. 2014, "Unified
//! particle physics", §4.2, which divides by the particle's own count alone). A lone
//! over-stretched spring ends within its bound after one pass. (Averaging by each
//! particle's own count, as the pass did before issue 43, divides a spring's two ends by
//! different numbers wherever the cloth is not symmetric: a cloth folding on a
//! frictionless floor walked sideways at 2.2e-3 m/s. Dividing by one number for the whole
//! cloth, 8, kept the momentum but a lone spring then lost an eighth of its excess per
//! pass: the round tablecloth over its table stretched to 0.79 instead of 0.17.)
//! Over-relaxing the average (×1.5) converged faster in the tests but made the
//! particles next to the pins jitter at 1 m/s in a hanging cloth, so there is none.
//!
//! After the springs, the pass applies the particle's tethers (long-range attachments,
//! Kim, Chentanez & Müller 2012): a particle farther than `(1 + τ)` times its rest
//! distance from a pin is put back on that sphere. Jacobi passes move a correction only
//! one spring per pass, so without tethers a cloth hung from two corners stretches without
//! bound as n grows (measured: max structural strain 1.5 at n = 128 and 9.4 at n = 256
//! with 2 passes per substep); with them the pins hold every particle directly.

use wide::f32x8;

use super::lanes::lane;
use super::springs::SlotSource;
use super::{Exec, Fetch, LANES, Lanes, for_each, v3, v4};
use clothlab_core::grid::{Rows, SLOT_OFFSETS, SLOTS, STRAIN_SLOTS, SpringSlot, TETHER_SLOTS, Tether, V4};
pub use clothlab_core::layout::STRAIN_AIM;
use clothlab_core::step_params::StepParams;

/// Every particle's count of over-stretched strain-limited springs at `pos`, into
/// `counts` (same length): what the pass that follows divides each spring by the larger
/// of its ends' counts of.
pub fn strain_count(exec: Exec, p: &StepParams, slots: &Rows<SpringSlot>, pos: &[V4], counts: &mut [f32]) {
    for_each(exec, counts, |i, c| *c = count_at(i, p, slots, |k| pos[k]));
}

/// The count of particle `i`: its strain-limited springs longer than `(1 + τ)·rest`,
/// decided as [`limit_at`] decides them (the same length, the same comparison).
#[inline(always)]
pub(crate) fn count_at(i: usize, p: &StepParams, slots: &(impl SlotSource + ?Sized), pos: impl Fetch) -> f32 {
    let stretch = 1.0 + p.strain_limit;
    let xi = v3(pos.at(i));
    let mut count = 0.0f32;
    slots.each(i, true, |s| {
        if s.neighbor < 0 {
            return;
        }
        let len = (v3(pos.at(s.neighbor as usize)) - xi).length();
        if len > stretch * s.rest {
            count += 1.0;
        }
    });
    count
}

/// One pass: reads `pos` and its [`strain_count`]s, writes the corrected positions to
/// `out` (same length). The kernel also updates the velocities ([`strain_vel`]).
pub fn strain_limit(
    exec: Exec,
    p: &StepParams,
    slots: &Rows<SpringSlot>,
    tethers: &[[Tether; TETHER_SLOTS]],
    pos: &[V4],
    counts: &[f32],
    out: &mut [V4],
) {
    for_each(exec, out, |i, o| *o = limit_at(i, p, slots, tethers, |k| pos[k], |k| counts[k]));
}

/// The velocity change of a pass that moved the positions from `pos` to `out`:
/// `v += (out − pos) · (1/dt)` (Provot's velocity update: the correction is motion, as it
/// was implicitly in Verlet's `x − x*`; pinned and grabbed particles do not move).
pub fn strain_vel(exec: Exec, p: &StepParams, pos: &[V4], out: &[V4], vel: &mut [V4]) {
    let inv_dt = 1.0 / p.dt;
    for_each(exec, vel, |i, v| *v = moved_vel(*v, pos[i], out[i], inv_dt));
}

/// [`strain_vel`] of one particle.
#[inline(always)]
pub(crate) fn moved_vel(v: V4, from: V4, to: V4, inv_dt: f32) -> V4 {
    v4(v3(v) + (v3(to) - v3(from)) * inv_dt, 0.0)
}

/// The pass for particle `i`; `counts` gives each particle's [`strain_count`].
#[inline(always)]
pub(crate) fn limit_at(
    i: usize,
    p: &StepParams,
    slots: &(impl SlotSource + ?Sized),
    tethers: &[[Tether; TETHER_SLOTS]],
    pos: impl Fetch,
    counts: impl Fn(usize) -> f32,
) -> V4 {
    let stretch = 1.0 + p.strain_limit;
    let aim = 1.0 + STRAIN_AIM * p.strain_limit;
    let mobility = |k: usize| if k as i32 == p.grab_index { 0.0 } else { pos.at(k)[3] };
    let xi = v3(pos.at(i));
    let wi = mobility(i);
    if wi == 0.0 {
        return pos.at(i);
    }
    let ci = counts(i);
    let mut corr = glam::Vec3::ZERO;
    let mut count = 0.0f32;
    // A count of 0: none of the particle's springs is over its limit (the count found
    // each as this pass would), so none adds anything; the kernels skip them alike.
    if ci > 0.0 {
        slots.each(i, true, |s| {
            if s.neighbor < 0 {
                return;
            }
            let b = s.neighbor as usize;
            let d = v3(pos.at(b)) - xi;
            let len = d.length();
            if len > stretch * s.rest {
                let wb = mobility(b);
                // share · excess / len / max(cᵢ, c_b) with share = wi / (wi + wb), in one
                // division: the same divisor at both ends, the momentum stays. (Dividing a
                // spring to a pin by cᵢ alone, where there is nothing to keep, measured a worse
                // drape: the thesis scene's max strain 0.105 against 0.104 at n = 64.) cᵢ ≥ 1
                // here when the counts are this pass's; at least 1 whatever they are.
                corr += d * (wi * (len - aim * s.rest) / ((wi + wb) * len * ci.max(counts(b)).max(1.0)));
                count += 1.0;
            }
        });
    }
    let mut x = if count > 0.0 { xi + corr } else { xi };
    for t in &tethers[i] {
        if t.pin < 0 {
            continue;
        }
        let pin = v3(pos.at(t.pin as usize));
        let d = x - pin;
        let len = d.length();
        let max = stretch * t.rest;
        if len > max {
            x = pin + d * (max / len);
        }
    }
    v4(x, pos.at(i)[3])
}

/// [`strain_limit`] row by row, the interior of each row eight particles at a time when
/// the grid's slots are uniform (`uni`); `lanes` must hold `pos`, `counts` its
/// [`strain_count`]s. Bit-identical to [`strain_limit`].
#[allow(clippy::too_many_arguments)]
pub fn strain_limit_rows(
    exec: Exec,
    p: &StepParams,
    slots: &Rows<SpringSlot>,
    uni: Option<&[SpringSlot; SLOTS]>,
    tethers: &[[Tether; TETHER_SLOTS]],
    lanes: &Lanes,
    pos: &[V4],
    counts: &[f32],
    out: &mut [V4],
) {
    let n = p.n as usize;
    super::for_each_row(exec, n, out, |j, row| {
        let base = j * n;
        match uni {
            Some(uni) if j >= 2 && j + 2 < n && n > 4 => {
                for i in [0, 1, n - 2, n - 1] {
                    row[i] = limit_at(base + i, p, slots, tethers, |k| pos[k], |k| counts[k]);
                }
                let len = n - 4;
                let groups = len / LANES;
                for g in 0..groups {
                    let a0 = base + 2 + g * LANES;
                    let o = &mut row[2 + g * LANES..2 + (g + 1) * LANES];
                    limit_lanes(a0, p, uni, tethers, lanes, pos, counts, o);
                }
                for (i, o) in row.iter_mut().enumerate().take(n - 2).skip(2 + groups * LANES) {
                    *o = limit_at(base + i, p, slots, tethers, |k| pos[k], |k| counts[k]);
                }
            }
            _ => {
                for (i, o) in row.iter_mut().enumerate() {
                    *o = limit_at(base + i, p, slots, tethers, |k| pos[k], |k| counts[k]);
                }
            }
        }
    });
}

/// Mobility of particles `start .. start + LANES`, with the grabbed particle's lane at 0.
#[inline(always)]
fn mobility_lanes(lanes: &Lanes, start: usize, grab: i32) -> f32x8 {
    let k = grab as isize - start as isize;
    if (0..LANES as isize).contains(&k) {
        let mut w = lanes.w(start).to_array();
        w[k as usize] = 0.0;
        f32x8::from(w)
    } else {
        lanes.w(start)
    }
}

/// [`limit_at`] for the eight interior particles from `a0`, written to `out[0 .. LANES]`.
#[allow(clippy::too_many_arguments)]
fn limit_lanes(
    a0: usize,
    p: &StepParams,
    uni: &[SpringSlot; SLOTS],
    tethers: &[[Tether; TETHER_SLOTS]],
    lanes: &Lanes,
    pos: &[V4],
    counts: &[f32],
    out: &mut [V4],
) {
    let n = p.n as isize;
    let stretch = 1.0 + p.strain_limit;
    let aim = 1.0 + STRAIN_AIM * p.strain_limit;
    let zero = f32x8::ZERO;
    let xi = lanes.pos3(a0);
    let wi = mobility_lanes(lanes, a0, p.grab_index);
    let ci = lane(counts, a0);
    let mut corr = [zero; 3];
    let mut count = zero;
    // As limit_at: a particle whose count is 0 takes no spring's share.
    let strained = ci.simd_gt(zero);
    let springs = if strained.any() { &uni[..STRAIN_SLOTS] } else { &[][..] };
    for (s, slot) in springs.iter().enumerate() {
        let (di, dj) = SLOT_OFFSETS[s];
        let b0 = (a0 as isize + di as isize + dj as isize * n) as usize;
        let xb = lanes.pos3(b0);
        let d = [xb[0] - xi[0], xb[1] - xi[1], xb[2] - xi[2]];
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let live = len.simd_gt(f32x8::splat(stretch * slot.rest)) & strained;
        let wb = mobility_lanes(lanes, b0, p.grab_index);
        let m = ci.max(lane(counts, b0)).max(f32x8::ONE);
        let f = wi * (len - f32x8::splat(aim * slot.rest)) / ((wi + wb) * len * m);
        for c in 0..3 {
            corr[c] += live.bitselect(d[c] * f, zero);
        }
        count += live.bitselect(f32x8::ONE, zero);
    }
    let has = count.simd_gt(zero);
    let mut x: [f32x8; 3] = std::array::from_fn(|c| has.bitselect(xi[c] + corr[c], xi[c]));
    let tg: &[[Tether; TETHER_SLOTS]; LANES] = tethers[a0..a0 + LANES].try_into().expect("LANES elements");
    for t in 0..TETHER_SLOTS {
        if tg.iter().all(|tk| tk[t].pin < 0) {
            continue;
        }
        // Empty slots read particle 0 and are masked out.
        let pins: [&V4; LANES] = std::array::from_fn(|k| &pos[tg[k][t].pin.max(0) as usize]);
        let pin: [f32x8; 3] =
            std::array::from_fn(|c| f32x8::from(std::array::from_fn::<f32, LANES, _>(|k| pins[k][c])));
        let rest = f32x8::from(std::array::from_fn::<f32, LANES, _>(|k| tg[k][t].rest));
        let live = f32x8::from(std::array::from_fn::<f32, LANES, _>(|k| (tg[k][t].pin >= 0) as u8 as f32));
        let d = [x[0] - pin[0], x[1] - pin[1], x[2] - pin[2]];
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let max = f32x8::splat(stretch) * rest;
        let apply = len.simd_gt(max) & live.simd_gt(zero);
        let q = max / len;
        for c in 0..3 {
            x[c] = apply.bitselect(pin[c] + d[c] * q, x[c]);
        }
    }
    // Pinned and grabbed particles keep their position.
    let fixed = wi.simd_eq(zero);
    let [x0, x1, x2] = std::array::from_fn(|c| fixed.bitselect(xi[c], x[c]).to_array());
    let src: &[V4; LANES] = pos[a0..a0 + LANES].try_into().expect("LANES elements");
    for (k, o) in out[..LANES].iter_mut().enumerate() {
        *o = [x0[k], x1[k], x2[k], src[k][3]];
    }
}
