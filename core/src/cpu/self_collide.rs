//! Self-collision: particles that are not neighbours in the grid are kept
//! `self_thickness` apart. The twins of the GPU kernels, in their order:
//!
//! 1. [`hash_count`]: each particle's cell (a cube of side `2·self_thickness`) is hashed to
//!    one of [`table_size`]`(n²)` buckets; the buckets count their particles (atomics on the GPU).
//! 2. [`hash_scan_blocks`], [`hash_scan_top`], [`hash_scan_add`]: an exclusive prefix sum
//!    of the counts gives every bucket the start of its range in one array of particle
//!    indices — per workgroup of [`WORKGROUP`] buckets, then over the workgroups' totals
//!    in one workgroup, then added back.
//! 3. [`hash_scatter`]: every particle writes its index into its bucket's range (atomics on
//!    the GPU, in any order), and [`hash_sort`] sorts each bucket's range (insertion sort:
//!    a bucket holds a few particles), so that what follows sums in one order everywhere.
//! 4. [`self_collide`]: every particle looks through the buckets of the 2 × 2 × 2 cells
//!    nearest to it (its own and the neighbour on its side per axis: cells are twice the
//!    thickness wide; a bucket two of them share once), refuses grid neighbours by the
//!    coordinates in the slot before loading them, and moves away from each particle
//!    closer than the thickness: a counting sort into a uniform grid, no per-particle lists.
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
//! `[count, start, cursor, block total]`; aux3: `[bucket of particle i, particle at slot
//! i as its grid coordinates `i | j << 12`, –, –]`), as `u32` bits in the `f32`
//! elements.

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

/// The cell of a point: `floor(x / s)` per axis for cells of side `s = 2t`, with `1/s`
/// passed in (a product is rounded alike everywhere, a quotient is not).
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

/// The 32-bit hash of a cell.
#[inline]
pub fn cell_hash(c: [i32; 3]) -> u32 {
    (c[0].wrapping_mul(PRIMES[0]) ^ c[1].wrapping_mul(PRIMES[1]) ^ c[2].wrapping_mul(PRIMES[2])) as u32
}

/// Bits of a grid coordinate in a slot's word (n ≤ 4096).
const COORD_BITS: u32 = 12;

/// What a slot holds for particle `i` of an `n`-wide grid: its grid coordinates,
/// `i | j << 12` — in index order as the particle's index is, and enough to refuse a grid
/// neighbour without loading it (below 2²⁴: as an `f32` element, a finite number).
#[inline]
pub fn slot_word(i: u32, n: u32) -> u32 {
    (i % n) | (i / n) << COORD_BITS
}

/// The grid coordinates `(i, j)` of a slot's word.
#[inline]
pub fn slot_coords(w: u32) -> (u32, u32) {
    (w & ((1 << COORD_BITS) - 1), w >> COORD_BITS)
}

/// The bucket of a cell among `size` (a power of two).
#[inline]
pub fn bucket(c: [i32; 3], size: u32) -> u32 {
    cell_hash(c) & (size - 1)
}

/// `1 / (2·self_thickness)`, the cells' inverse size (computed once, in [`StepParams::new`]).
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

/// Step 3a: every particle's [`slot_word`] into the next free slot of its bucket's range
/// (`sorted[slot].y`), in index order (a GPU's order differs; [`hash_sort`] follows).
/// Buckets and cursors out of range (never from [`hash_count`] and the scans) are skipped.
pub fn hash_scatter(p: &StepParams, cells: &mut [V4], sorted: &mut [V4]) {
    for i in 0..sorted.len() {
        let b = bits(sorted[i][0]) as usize;
        let Some(cell) = cells.get_mut(b) else { continue };
        let slot = bits(cell[2]);
        cell[2] = word(slot.wrapping_add(1));
        if let Some(s) = sorted.get_mut(slot as usize) {
            s[1] = word(slot_word(i as u32, p.n));
        }
    }
}

/// The hash's two buffers among the integrators' scratch buffers (`aux`, [`super::AUX`]
/// of them): aux2 (cells) and aux3 (slots).
pub fn hash_buffers(aux: &mut [Vec<V4>]) -> (&mut [V4], &mut [V4]) {
    let [_, _, cells, sorted, ..] = aux else { panic!("the {} integrator scratch buffers", super::AUX) };
    (cells, sorted)
}

/// The range `[start, end)` of bucket `c`'s particles in `sorted`, clamped to it.
#[inline]
fn range(c: &V4, len: usize) -> (usize, usize) {
    let start = (bits(c[1]) as usize).min(len);
    (start, (start + bits(c[0]) as usize).min(len))
}

/// Step 3b: each bucket's range sorted by particle (insertion sort), and the bounding box
/// of its particles' grid coordinates into `cells[b].z` (smallest i and j, as a slot word)
/// and `.w` (largest), where the cursor and the block total were: a probe skips a bucket
/// whose particles are all grid neighbours without reading them.
pub fn hash_sort(cells: &mut [V4], sorted: &mut [V4]) {
    let size = table_size(cells.len()) as usize;
    for c in &mut cells[..size] {
        let (start, end) = range(c, sorted.len());
        if start == end {
            continue;
        }
        for k in start + 1..end {
            let v = sorted[k][1];
            let mut m = k;
            while m > start && bits(sorted[m - 1][1]) > bits(v) {
                sorted[m][1] = sorted[m - 1][1];
                m -= 1;
            }
            sorted[m][1] = v;
        }
        let (mut lo, mut hi) = ((u32::MAX, u32::MAX), (0, 0));
        for s in &sorted[start..end] {
            let (i, j) = slot_coords(bits(s[1]));
            lo = (lo.0.min(i), lo.1.min(j));
            hi = (hi.0.max(i), hi.1.max(j));
        }
        c[2] = word(lo.0 | lo.1 << COORD_BITS);
        c[3] = word(hi.0 | hi.1 << COORD_BITS);
    }
}

/// Whether every particle of bucket `c` (by its bounding box) is within the springs'
/// 5 × 5 stencil around `me`: nothing there may collide with it.
#[inline]
fn all_neighbours(c: &V4, me: (i32, i32)) -> bool {
    let (lo, hi) = (slot_coords(bits(c[2])), slot_coords(bits(c[3])));
    lo.0 as i32 >= me.0 - 2 && hi.0 as i32 <= me.0 + 2 && lo.1 as i32 >= me.1 - 2 && hi.1 as i32 <= me.1 + 2
}

/// Steps 1 to 3: the hash of `pos` in `cells` and `sorted` (one element per particle).
pub fn build_hash(p: &StepParams, pos: &[V4], cells: &mut [V4], sorted: &mut [V4]) {
    cells.iter_mut().for_each(|c| *c = [0.0; 4]);
    hash_count(p, pos, cells, sorted);
    hash_scan_blocks(cells);
    hash_scan_top(cells);
    hash_scan_add(cells);
    hash_scatter(p, cells, sorted);
    hash_sort(cells, sorted);
}

/// Whether particles `a` and `b` of an `n`-wide grid may collide: outside the springs'
/// 5 × 5 stencil and farther apart at rest than twice the thickness.
#[inline]
pub fn candidates(p: &StepParams, a: u32, b: u32) -> bool {
    let ((ai, aj), (bi, bj)) = ((a % p.n, a / p.n), (b % p.n, b / p.n));
    candidate_coords(p, (ai as i32, aj as i32), (bi as i32, bj as i32))
}

/// [`candidates`] by grid coordinates.
#[inline]
pub fn candidate_coords(p: &StepParams, a: (i32, i32), b: (i32, i32)) -> bool {
    let (di, dj) = (a.0 - b.0, a.1 - b.1);
    if di.abs() <= 2 && dj.abs() <= 2 {
        return false;
    }
    let t2 = 2.0 * p.self_thickness;
    ((di * di + dj * dj) as f32) * (p.spacing * p.spacing) > t2 * t2
}

/// Cell `k` (0 ..= 7, x fastest) of the 2 × 2 × 2 around a point in cell `c`: per axis,
/// `c` or the neighbour on the point's side (`side`: ±1). A point within `t` of the
/// point lies in one of them, cells being `2t` wide.
#[inline]
fn around(c: [i32; 3], side: [i32; 3], k: usize) -> [i32; 3] {
    std::array::from_fn(|a| c[a].wrapping_add(if k >> a & 1 == 1 { side[a] } else { 0 }))
}

/// Per axis, the side of its cell a point lies on: +1 in the upper half, −1 in the lower.
#[inline]
fn sides(x: &V4, c: [i32; 3], inv: f32) -> [i32; 3] {
    std::array::from_fn(|a| {
        let v = (x[a] * inv).clamp(-CELL_LIMIT, CELL_LIMIT);
        if v - c[a] as f32 >= 0.5 { 1 } else { -1 }
    })
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
    let side = sides(&x4, c, inv);
    let me = ((i as u32 % p.n) as i32, (i as u32 / p.n) as i32);
    let mut buckets = [0u32; 8];
    let mut delta = [0.0f32; 3];
    for k in 0..8 {
        let b = bucket(around(c, side, k), size);
        buckets[k] = b;
        // Two of the 8 cells may share a bucket: each bucket once, so each particle once
        // (whichever of the cells it is in: the distance decides).
        if buckets[..k].contains(&b) {
            continue;
        }
        let cell = &cells[b as usize];
        let (start, end) = range(cell, sorted.len());
        if start == end || all_neighbours(cell, me) {
            continue;
        }
        for s in &sorted[start..end] {
            // Grid neighbours (most entries of a flat cloth) refused before loading them.
            let (qi, qj) = slot_coords(bits(s[1]));
            let q = (qj * p.n + qi) as usize;
            if qi >= p.n || q >= pos.len() || !candidate_coords(p, me, (qi as i32, qj as i32)) {
                continue;
            }
            let y4 = pos[q];
            let e = [x4[0] - y4[0], x4[1] - y4[1], x4[2] - y4[2]];
            let d2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
            if d2 >= t * t || d2 < 1e-12 {
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
            let ids: Vec<u32> = sorted[start..end]
                .iter()
                .map(|s| {
                    let (i, j) = slot_coords(bits(s[1]));
                    j * n + i
                })
                .collect();
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
