//! `springs` — the spring force of thesis eq. 4.35 with spring damping:
//! `F_a = -[ks (|L| - r) + kd (L'·L)/|L|] L/|L|`, `L = x_a - x_b`, `L' = v_a - v_b`.

use glam::Vec3;
use wide::f32x8;

use super::forces::{forces_at, forces_consts, forces_consts_w};
use super::{Exec, Fetch, LANES, Lanes, for_each, load3, store3, v3, v4};
use clothlab_core::grid::{Rows, SLOT_OFFSETS, SLOTS, Spring, SpringSlot, V4};
use clothlab_core::step_params::StepParams;

/// Where a particle's spring slots come from: the table, or (for the fused sweep) the
/// regular grid's, computed from the particle's place.
pub(crate) trait SlotSource {
    /// `f` on each slot of particle `i` in order: all of them, or (`head`) those the strain
    /// limit holds (the first ones: the row's head). One call per particle, so that a
    /// table's row is found once, not per slot.
    fn each(&self, i: usize, head: bool, f: impl FnMut(&SpringSlot));
}

impl SlotSource for Rows<SpringSlot> {
    #[inline(always)]
    fn each(&self, i: usize, head: bool, f: impl FnMut(&SpringSlot)) {
        let row = if head { self.head(i) } else { self.row(i) };
        row.iter().for_each(f);
    }
}

/// The slots of a grid whose table is regular ([`clothlab_core::ClothTopology::grid_slots`]):
/// slot `s` holds `uni[s]` wherever the neighbour at its offset exists.
pub(crate) struct GridSlots<'a> {
    pub n: usize,
    pub uni: &'a [SpringSlot; SLOTS],
}

impl SlotSource for GridSlots<'_> {
    #[inline(always)]
    fn each(&self, i: usize, head: bool, mut f: impl FnMut(&SpringSlot)) {
        let count = if head { clothlab_core::grid::STRAIN_SLOTS } else { SLOTS };
        for s in 0..count {
            f(&self.slot(i, s));
        }
    }
}

impl GridSlots<'_> {
    /// Slot `s` of particle `i`.
    #[inline(always)]
    fn slot(&self, i: usize, s: usize) -> SpringSlot {
        let n = self.n as isize;
        let (di, dj) = SLOT_OFFSETS[s];
        let (x, y) = ((i as isize % n) + di as isize, (i as isize / n) + dj as isize);
        if x < 0 || y < 0 || x >= n || y >= n {
            return SpringSlot::EMPTY;
        }
        SpringSlot { neighbor: (y * n + x) as i32, ..self.uni[s] }
    }
}

/// Force on end `a` of a spring with `l = x_a - x_b` and `dv = v_a - v_b`.
#[inline(always)]
pub(crate) fn spring_force(l: Vec3, dv: Vec3, s: &SpringSlot) -> Vec3 {
    let len = l.length();
    if len <= f32::MIN_POSITIVE {
        return Vec3::ZERO;
    }
    // One division per spring, not three: the kernels are bound by divisions and roots.
    let dir = l * (1.0 / len);
    -(s.ks * (len - s.rest) + s.kd * dv.dot(dir)) * dir
}

/// Gather (optimized kernels, CPU solvers): each particle adds its 12 slots in slot order.
pub fn springs(exec: Exec, slots: &Rows<SpringSlot>, pos: &[V4], vel: &[V4], force: &mut [V4]) {
    for_each(exec, force, |i, f| *f = gather_at(i, slots, |k| pos[k], |k| vel[k], *f));
}

/// The gather of particle `i`: `f` plus its springs' forces in slot order.
#[inline(always)]
pub(crate) fn gather_at(i: usize, slots: &(impl SlotSource + ?Sized), pos: impl Fetch, vel: impl Fetch, f: V4) -> V4 {
    let xa = v3(pos.at(i));
    let va = v3(vel.at(i));
    let mut acc = v3(f);
    slots.each(i, false, |s| {
        let Some(b) = s.other() else { return };
        let xb = v3(pos.at(b));
        let vb = v3(vel.at(b));
        acc += spring_force(xa - xb, va - vb, s);
    });
    v4(acc, 0.0)
}

/// [`springs`], row by row, with the interior of each row on `springs_interior` when
/// the grid's slots are uniform (`uni`); `lanes` must hold `pos` and `vel`.
/// Bit-identical to [`springs`].
#[allow(clippy::too_many_arguments)]
pub fn springs_rows(
    exec: Exec,
    n: usize,
    slots: &Rows<SpringSlot>,
    uni: Option<&[SpringSlot; SLOTS]>,
    forces: Option<&StepParams>,
    lanes: &Lanes,
    pos: &[V4],
    vel: &[V4],
    force: &mut [V4],
) {
    // With `forces`, each particle first gets `forces` (gravity and drag), then its springs:
    // the two kernels fused into one sweep, bit-identical to running them in turn.
    let ext = forces.map(forces_consts);
    // Particle by particle, each with its own mass (a mesh's; a grid's are the reference).
    let gather = |i: usize, f: V4| {
        let f = match forces {
            Some(p) => {
                let (g, drag) = forces_consts_w(p, pos[i][3]);
                forces_at(f, vel[i], g, drag)
            }
            None => f,
        };
        gather_at(i, slots, |k| pos[k], |k| vel[k], f)
    };
    let offs: [isize; SLOTS] = SLOT_OFFSETS.map(|(di, dj)| di as isize + dj as isize * n as isize);
    super::for_each_row(exec, n, force, |j, row| {
        let base = j * n;
        match uni {
            Some(uni) if j >= 2 && j + 2 < n && n > 4 => {
                for i in [0, 1, n - 2, n - 1] {
                    row[i] = gather(base + i, row[i]);
                }
                springs_interior(base + 2, n - 4, &offs, uni, ext, lanes, pos, vel, &mut row[2..n - 2]);
            }
            _ => {
                for (i, f) in row.iter_mut().enumerate() {
                    *f = gather(base + i, *f);
                }
            }
        }
    });
}

/// Scatter (twin of the naive kernel): each spring adds its force to both ends. The
/// summation order differs from [`springs`], so results agree only up to rounding.
pub fn springs_scatter(springs: &[Spring], pos: &[V4], vel: &[V4], force: &mut [V4]) {
    for s in springs {
        let (a, b) = (s.a as usize, s.b as usize);
        let (xa, xb) = (v3(pos[a]), v3(pos[b]));
        let (va, vb) = (v3(vel[a]), v3(vel[b]));
        let slot = SpringSlot { neighbor: s.b as i32, rest: s.rest, ks: s.ks, kd: s.kd };
        let fa = spring_force(xa - xb, va - vb, &slot);
        force[a] = v4(v3(force[a]) + fa, 0.0);
        force[b] = v4(v3(force[b]) - fa, 0.0);
    }
}

/// Fast path for `len` interior particles starting at `base` (all 12 slots present, all
/// springs of a slot with the same constants `uni[s]`): the same arithmetic in the same
/// order as [`springs`], without the table and the branches, eight particles at a time
/// in SIMD lanes (`wide::f32x8`; lane-wise IEEE operations, so the bits are the twin's).
#[allow(clippy::too_many_arguments)]
pub(crate) fn springs_interior(
    base: usize,
    len: usize,
    offs: &[isize; SLOTS],
    uni: &[SpringSlot; SLOTS],
    ext: Option<(Vec3, f32)>,
    lanes: &Lanes,
    pos: &[V4],
    vel: &[V4],
    force: &mut [V4],
) {
    let groups = len / LANES;
    let zero = f32x8::ZERO;
    let tiny = f32x8::splat(f32::MIN_POSITIVE);
    for g in 0..groups {
        let a0 = base + g * LANES;
        let xa = lanes.pos3(a0);
        let va = lanes.vel3(a0);
        let fo = &mut force[g * LANES..(g + 1) * LANES];
        let mut acc = load3(fo, 0);
        if let Some((g, drag)) = ext {
            let (g, drag) = ([f32x8::splat(g.x), f32x8::splat(g.y), f32x8::splat(g.z)], f32x8::splat(drag));
            for c in 0..3 {
                acc[c] = (acc[c] + g[c]) - va[c] * drag;
            }
        }
        for (s, slot) in uni.iter().enumerate() {
            let b0 = (a0 as isize + offs[s]) as usize;
            let xb = lanes.pos3(b0);
            let vb = lanes.vel3(b0);
            let l = [xa[0] - xb[0], xa[1] - xb[1], xa[2] - xb[2]];
            let dv = [va[0] - vb[0], va[1] - vb[1], va[2] - vb[2]];
            let len = (l[0] * l[0] + l[1] * l[1] + l[2] * l[2]).sqrt();
            let inv = f32x8::ONE / len;
            let dir = [l[0] * inv, l[1] * inv, l[2] * inv];
            let dot = dv[0] * dir[0] + dv[1] * dir[1] + dv[2] * dir[2];
            let m = -(f32x8::splat(slot.ks) * (len - f32x8::splat(slot.rest)) + f32x8::splat(slot.kd) * dot);
            let live = len.simd_gt(tiny);
            for c in 0..3 {
                acc[c] += live.bitselect(m * dir[c], zero);
            }
        }
        store3(fo, &acc);
    }
    // The remainder, one particle at a time with the same arithmetic.
    for (i, f) in force.iter_mut().enumerate().take(len).skip(groups * LANES) {
        let a = base + i;
        let xa = v3(pos[a]);
        let va = v3(vel[a]);
        let f0 = match ext {
            Some((g, drag)) => forces_at(*f, vel[a], g, drag),
            None => *f,
        };
        let mut acc = v3(f0);
        for (s, slot) in uni.iter().enumerate() {
            let b = (a as isize + offs[s]) as usize;
            let xb = v3(pos[b]);
            acc += spring_force(xa - xb, va - v3(vel[b]), slot);
        }
        *f = v4(acc, 0.0);
    }
}
