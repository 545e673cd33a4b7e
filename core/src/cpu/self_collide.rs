//! Self-collision: particles that are not neighbours in the grid are kept
//! `self_thickness` apart. The twins of the GPU kernels, in their order:
//!
//! 1. [`hash_count`]: each particle's cell (a cube of side `self_thickness`) is hashed to
//!    one of [`table_size`]`(n²)` buckets; the buckets count their particles (atomics on the GPU).
//! 2. [`hash_scan_blocks`], [`hash_scan_top`], [`hash_scan_add`]: an exclusive prefix sum
//!    of the counts gives every bucket the start of its range in one array of particle
//!    indices — per workgroup of [`WORKGROUP`] buckets, then over the workgroups' totals
//!    in one workgroup, then added back.
//! 3. [`hash_scatter`]: every particle writes its index into its bucket's range (atomics on
//!    the GPU, in any order), and [`hash_sort`] sorts each bucket's range (insertion sort:
//!    a bucket holds a few particles), so that what follows sums in one order everywhere.
//! 4. [`self_collide`]: every particle looks through the buckets of the 27 cells around
//!    its own and moves away from each particle closer than the thickness: a counting
//!    sort into a uniform grid, no per-particle lists.
//!
//! A pair is a candidate when its grid offset is outside the 5 × 5 stencil of the springs
//! and its rest distance exceeds twice the thickness (closer ones would be pushed apart by
//! the flat cloth itself). Each particle of a pair closer than `t` moves half of `t − d`
//! away along the line between them (all of it when the other is pinned); its velocity
//! loses its component into the contact. This keeps particles apart, not triangles: two
//! sheets whose particles are farther apart than the thickness can pass between each
//! other's particles, and an edge can cross an edge, when the cloth is coarse next to its
//! thickness (spacing > t·√2) or moves more than the thickness in one substep.
//!
//! The hash lives in integrator scratch buffers that are dead by then (aux2: per bucket
//! `[count, start, cursor, block total]`; aux3: per particle `[bucket, particle at this
//! slot, –, –]`), as `u32` bits in the `f32` elements.

use crate::grid::{StepParams, V4};
use crate::layout::WORKGROUP;

use super::{Exec, for_each2};

/// The hash's primes (Teschner et al. 2003).
pub const PRIMES: [i32; 3] = [92_837_111, 689_287_499, 283_923_481];
/// Cell coordinates are clamped to ±1e9 before they are converted to integers.
const CELL_LIMIT: f32 = 1e9;

#[inline]
fn bits(v: f32) -> u32 {
    v.to_bits()
}

#[inline]
fn word(v: u32) -> f32 {
    f32::from_bits(v)
}

/// The cell of a point: `floor(x / t)` per axis, with `1/t` passed in (a product is
/// rounded alike everywhere, a quotient is not).
#[inline]
pub fn cell_of(x: &V4, inv_cell: f32) -> [i32; 3] {
    std::array::from_fn(|k| {
        // floor without libm's call (baseline x86-64 has no rounding instruction): the
        // truncation, one less below zero where it was not exact. Equal to floor for
        // every value in ±1e9.
        let v = (x[k] * inv_cell).clamp(-CELL_LIMIT, CELL_LIMIT);
        let t = v as i32;
        t - i32::from((t as f32) > v)
    })
}

/// Buckets of a hash over `len` elements: the largest power of two not above it (at
/// most two particles a bucket on average; the bucket is a mask, not a division).
#[inline]
pub fn table_size(len: usize) -> u32 {
    let len = len.max(1) as u32;
    1 << (31 - len.leading_zeros())
}

/// The bucket of a cell among `size` (a power of two).
#[inline]
pub fn bucket(c: [i32; 3], size: u32) -> u32 {
    let h = c[0].wrapping_mul(PRIMES[0]) ^ c[1].wrapping_mul(PRIMES[1]) ^ c[2].wrapping_mul(PRIMES[2]);
    (h as u32) & (size - 1)
}

/// `1 / self_thickness`, the cells' inverse size (computed once, in [`StepParams::new`]).
#[inline]
pub fn inv_cell(p: &StepParams) -> f32 {
    p.inv_cell
}

/// Step 1: each particle's bucket into `sorted[i].x`, the buckets' counts into
/// `cells[b].x` (cleared before).
pub fn hash_count(p: &StepParams, pos: &[V4], cells: &mut [V4], sorted: &mut [V4]) {
    let (size, inv) = (table_size(cells.len()), inv_cell(p));
    for (x, s) in pos.iter().zip(sorted.iter_mut()) {
        let b = bucket(cell_of(x, inv), size);
        s[0] = word(b);
        let c = &mut cells[b as usize][0];
        *c = word(bits(*c).wrapping_add(1));
    }
}

/// Step 2a: within each workgroup of buckets, the exclusive prefix of the counts into
/// `cells[b].y`, and the workgroup's total into `cells[g].w`.
pub fn hash_scan_blocks(cells: &mut [V4]) {
    let size = table_size(cells.len()) as usize;
    let cells = &mut cells[..size];
    let w = WORKGROUP as usize;
    for g in 0..cells.len().div_ceil(w) {
        let mut acc = 0u32;
        for b in g * w..((g + 1) * w).min(cells.len()) {
            cells[b][1] = word(acc);
            acc = acc.wrapping_add(bits(cells[b][0]));
        }
        cells[g][3] = word(acc);
    }
}

/// Step 2b: the exclusive prefix of the workgroups' totals, in place (`cells[g].w`).
pub fn hash_scan_top(cells: &mut [V4]) {
    let size = table_size(cells.len()) as usize;
    let cells = &mut cells[..size];
    let groups = cells.len().div_ceil(WORKGROUP as usize);
    let mut acc = 0u32;
    for c in cells.iter_mut().take(groups) {
        let total = bits(c[3]);
        c[3] = word(acc);
        acc = acc.wrapping_add(total);
    }
}

/// Step 2c: each bucket's start (`cells[b].y`, its workgroup's offset added) and its
/// scatter cursor (`cells[b].z`, the same).
pub fn hash_scan_add(cells: &mut [V4]) {
    let size = table_size(cells.len()) as usize;
    let cells = &mut cells[..size];
    let w = WORKGROUP as usize;
    for b in 0..cells.len() {
        let start = bits(cells[b][1]).wrapping_add(bits(cells[b / w][3]));
        cells[b][1] = word(start);
        cells[b][2] = word(start);
    }
}

/// Step 3a: every particle's index into the next free slot of its bucket's range
/// (`sorted[slot].y`), in index order (a GPU's order differs; [`hash_sort`] follows).
/// Buckets and cursors out of range (never from [`hash_count`] and the scans) are skipped.
pub fn hash_scatter(cells: &mut [V4], sorted: &mut [V4]) {
    for i in 0..sorted.len() {
        let b = bits(sorted[i][0]) as usize;
        let Some(cell) = cells.get_mut(b) else { continue };
        let slot = bits(cell[2]);
        cell[2] = word(slot.wrapping_add(1));
        if let Some(s) = sorted.get_mut(slot as usize) {
            s[1] = word(i as u32);
        }
    }
}

/// The range `[start, end)` of bucket `c`'s particles in `sorted`, clamped to it.
#[inline]
fn range(c: &V4, len: usize) -> (usize, usize) {
    let start = (bits(c[1]) as usize).min(len);
    (start, (start + bits(c[0]) as usize).min(len))
}

/// Step 3b: each bucket's range sorted by particle index (insertion sort).
pub fn hash_sort(cells: &[V4], sorted: &mut [V4]) {
    for c in &cells[..table_size(cells.len()) as usize] {
        let (start, end) = range(c, sorted.len());
        for k in start + 1..end {
            let v = bits(sorted[k][1]);
            let mut m = k;
            while m > start && bits(sorted[m - 1][1]) > v {
                sorted[m][1] = sorted[m - 1][1];
                m -= 1;
            }
            sorted[m][1] = word(v);
        }
    }
}

/// Steps 1 to 3: the hash of `pos` in `cells` and `sorted` (one element per particle).
pub fn build_hash(p: &StepParams, pos: &[V4], cells: &mut [V4], sorted: &mut [V4]) {
    cells.iter_mut().for_each(|c| *c = [0.0; 4]);
    hash_count(p, pos, cells, sorted);
    hash_scan_blocks(cells);
    hash_scan_top(cells);
    hash_scan_add(cells);
    hash_scatter(cells, sorted);
    hash_sort(cells, sorted);
}

/// Whether particles `a` and `b` of an `n`-wide grid may collide: outside the springs'
/// 5 × 5 stencil and farther apart at rest than twice the thickness.
#[inline]
pub fn candidates(p: &StepParams, a: u32, b: u32) -> bool {
    let (ai, aj, bi, bj) = ((a % p.n) as i32, (a / p.n) as i32, (b % p.n) as i32, (b / p.n) as i32);
    let (di, dj) = (ai - bi, aj - bj);
    if di.abs() <= 2 && dj.abs() <= 2 {
        return false;
    }
    let t2 = 2.0 * p.self_thickness;
    ((di * di + dj * dj) as f32) * (p.spacing * p.spacing) > t2 * t2
}

/// The 27 cells around `c` (and `c`), x fastest.
#[inline]
fn around(c: [i32; 3], k: usize) -> [i32; 3] {
    let d = [(k % 3) as i32 - 1, ((k / 3) % 3) as i32 - 1, (k / 9) as i32 - 1];
    [c[0].wrapping_add(d[0]), c[1].wrapping_add(d[1]), c[2].wrapping_add(d[2])]
}

/// Particle `i`'s new position and previous position: pushed out of every candidate
/// closer than the thickness, its velocity into the contact removed.
pub fn self_collide_at(p: &StepParams, i: usize, pos: &[V4], prev: V4, cells: &[V4], sorted: &[V4]) -> (V4, V4) {
    let x4 = pos[i];
    if x4[3] == 0.0 || i as i32 == p.grab_index {
        return (x4, prev);
    }
    let t = p.self_thickness;
    let size = table_size(cells.len());
    let inv = inv_cell(p);
    let c = cell_of(&x4, inv);
    let mut delta = [0.0f32; 3];
    for k in 0..27 {
        let cell = around(c, k);
        let (start, end) = range(&cells[bucket(cell, size) as usize], sorted.len());
        for s in &sorted[start..end] {
            let q = bits(s[1]) as usize;
            if q == i || q >= pos.len() {
                continue;
            }
            let y4 = pos[q];
            // Only the particles of this cell: another cell hashed to the same bucket is
            // one of the 27 itself (each particle counted once) or far away.
            if cell_of(&y4, inv) != cell {
                continue;
            }
            let e = [x4[0] - y4[0], x4[1] - y4[1], x4[2] - y4[2]];
            let d2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
            if d2 >= t * t || d2 < 1e-12 || !candidates(p, i as u32, q as u32) {
                continue;
            }
            let d = d2.sqrt();
            let share = if y4[3] == 0.0 { 1.0 } else { 0.5 };
            let s = (t - d) / d * share;
            for a in 0..3 {
                delta[a] += e[a] * s;
            }
        }
    }
    let dd = delta[0] * delta[0] + delta[1] * delta[1] + delta[2] * delta[2];
    if dd == 0.0 {
        return (x4, prev);
    }
    let x = [x4[0] + delta[0], x4[1] + delta[1], x4[2] + delta[2]];
    let mut u = [x4[0] - prev[0], x4[1] - prev[1], x4[2] - prev[2]];
    let len = dd.sqrt();
    let nrm = [delta[0] / len, delta[1] / len, delta[2] / len];
    let un = u[0] * nrm[0] + u[1] * nrm[1] + u[2] * nrm[2];
    if un < 0.0 {
        for a in 0..3 {
            u[a] -= un * nrm[a];
        }
    }
    ([x[0], x[1], x[2], x4[3]], [x[0] - u[0], x[1] - u[1], x[2] - u[2], prev[3]])
}

/// Step 4: every particle pushed out of its close candidates into `pos_out`, its `prev`
/// updated in place (each element read and written only by its own particle).
pub fn self_collide(
    exec: Exec,
    p: &StepParams,
    pos: &[V4],
    prev: &mut [V4],
    cells: &[V4],
    sorted: &[V4],
    pos_out: &mut [V4],
) {
    for_each2(exec, pos_out, prev, |i, o, q| {
        let (x, xp) = self_collide_at(p, i, pos, *q, cells, sorted);
        *o = x;
        *q = xp;
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::SimParams;
    use crate::scene::Scene;

    fn params(n: u32, t: f32) -> StepParams {
        let sp = SimParams { self_collision: true, self_thickness: t, ..SimParams::default() };
        StepParams::new(&sp, &Scene::with_n(n), None)
    }

    #[test]
    fn the_hash_lists_every_particle_once_in_its_bucket_sorted() {
        // 300 particles scattered over a few cells, so that buckets hold several.
        let n = 17;
        let p = params(n, 0.05);
        let np = (n * n) as usize;
        let pos: Vec<V4> =
            (0..np).map(|i| [(i % 7) as f32 * 0.031, (i % 5) as f32 * 0.043, (i % 3) as f32 * 0.07, 1.0]).collect();
        let (mut cells, mut sorted) = (vec![[0.0; 4]; np], vec![[0.0; 4]; np]);
        build_hash(&p, &pos, &mut cells, &mut sorted);
        let mut listed = vec![0; np];
        assert_eq!(table_size(np), 256);
        for (b, c) in cells[..256].iter().enumerate() {
            let (start, end) = range(c, np);
            let ids: Vec<u32> = sorted[start..end].iter().map(|s| bits(s[1])).collect();
            assert!(ids.windows(2).all(|w| w[0] < w[1]), "bucket {b}: {ids:?} not sorted");
            for &q in &ids {
                assert_eq!(bucket(cell_of(&pos[q as usize], inv_cell(&p)), table_size(np)), b as u32);
                listed[q as usize] += 1;
            }
        }
        assert!(listed.iter().all(|&c| c == 1), "every particle listed exactly once");
        // The counts add up, and the ranges tile the array.
        let total: u32 = cells.iter().map(|c| bits(c[0])).sum();
        assert_eq!(total as usize, np);
    }

    #[test]
    fn two_particles_closer_than_the_thickness_end_exactly_the_thickness_apart() {
        // Two far-apart particles of the grid (not neighbours) 0.6 t apart: each moves
        // 0.2 t away; the one moving towards the other loses that velocity.
        let n = 16;
        let t = 0.02;
        let p = params(n, t);
        let np = (n * n) as usize;
        let mut pos: Vec<V4> = (0..np).map(|i| [i as f32 * 10.0, 5.0, 0.0, 1.0]).collect();
        let (a, b) = (0usize, np - 1);
        pos[a] = [0.3, 1.0, 0.0, 1.0];
        pos[b] = [0.3 + 0.6 * t, 1.0, 0.0, 1.0];
        let mut prev = pos.clone();
        prev[a][0] -= 0.001; // a moves towards b at 1 mm a substep
        let (mut cells, mut sorted) = (vec![[0.0; 4]; np], vec![[0.0; 4]; np]);
        build_hash(&p, &pos, &mut cells, &mut sorted);
        let mut out = pos.clone();
        self_collide(Exec::Serial, &p, &pos, &mut prev, &cells, &sorted, &mut out);
        let gap = out[b][0] - out[a][0];
        assert!((gap - t).abs() < 1e-7, "gap {gap}, thickness {t}");
        assert!((out[a][0] - (0.3 - 0.2 * t)).abs() < 1e-7);
        // a's velocity into the contact (+x) is gone; b was at rest.
        assert!((out[a][0] - prev[a][0]).abs() < 1e-9, "a still moves {} m a substep", out[a][0] - prev[a][0]);
        assert_eq!(out[b][0] - prev[b][0], 0.0);
        // Everyone else is untouched.
        assert_eq!(out[1], pos[1]);
    }

    #[test]
    fn cells_are_floors_and_tables_powers_of_two() {
        for v in [-2.5f32, -2.0, -1e-7, 0.0, 1e-7, 0.999_999_9, 1.0, 3.7, -1e12, 1e12] {
            let want = v.floor().clamp(-CELL_LIMIT, CELL_LIMIT) as i32;
            assert_eq!(cell_of(&[v, 0.0, 0.0, 0.0], 1.0)[0], want, "{v}");
        }
        assert_eq!([table_size(1), table_size(4), table_size(289), table_size(4096)], [1, 4, 256, 4096]);
    }

    #[test]
    fn grid_neighbours_are_never_candidates() {
        let p = params(64, 0.01);
        let at = |i: u32, j: u32| j * 64 + i;
        assert!(!candidates(&p, at(10, 10), at(12, 12)));
        assert!(!candidates(&p, at(10, 10), at(8, 11)));
        assert!(candidates(&p, at(10, 10), at(13, 10)));
        // Rest distance 3 spacings = 0.095 m; a thickness of 0.05 m excludes it (2t = 0.1).
        let thick = params(64, 0.05);
        assert!(!candidates(&thick, at(10, 10), at(13, 10)));
        assert!(candidates(&thick, at(10, 10), at(14, 10)));
    }
}
