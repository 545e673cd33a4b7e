//! Self-collision: particles that are not neighbours in the grid are kept
//! `self_thickness` apart. The twins of the GPU kernels, in their order:
//!
//! 1. [`hash_count`]: each particle's cell (a cube of side `t = self_thickness`) is hashed
//!    to one of [`table_size`]`(n²)` buckets (four times the largest power of two not
//!    above n²); the buckets count their particles, and so do their blocks of
//!    [`WORKGROUP`] buckets (atomics on the GPU). A cell's bucket is its row's hash plus
//!    its x ([`bucket`]): the three cells of a row in x are three consecutive buckets,
//!    whose particles lie in one range of the sorted array.
//! 2. [`hash_scan_top`], [`hash_scan_blocks`]: an inclusive prefix sum of the counts gives
//!    every bucket the end of its range in one array of particles — first the blocks'
//!    offsets (the exclusive prefix of their totals, in one workgroup), then within each
//!    block from its offset. (Counting the blocks' totals with the buckets' saves the
//!    third pass that adds the offsets back: on lavapipe a dispatch costs about 50 µs.)
//! 3. [`hash_scatter`]: every particle copies its position and slot word into the slot
//!    before its bucket's end (atomics on the GPU, in any order), which leaves each
//!    bucket's word at the start of its range:
//!    bucket `b`'s particles are the slots `[cells[b], cells[b + 1])`. No sort: the
//!    response sums in fixed point, which is the same in any order.
//! 4. [`self_collide`]: every particle looks through the cells of the 3 × 3 × 3 around
//!    its own that the sphere of radius `t` around it reaches — row by row: nine rows in
//!    x, a row the sphere misses skipped, the others trimmed to the cells it reaches, each
//!    one range of the sorted array read between two words of `cells` (rows never share
//!    a bucket: [`row_start`]) — refuses entries of other rows and grid neighbours by the
//!    slot's word, and moves away from each particle closer than the thickness:
//!    a counting sort into a uniform grid, no per-particle lists. (The GPU kernel walks
//!    two row neighbours' rows at once and tests no entry's cell or tag: a particle
//!    closer than `t` lies in a cell the walk reads once, so each finds the same
//!    contacts, summed in another order.)
//!
//! A pair is a candidate when its grid offset is outside the 5 × 5 stencil of the springs
//! and its rest distance exceeds twice the thickness (closer ones would be pushed apart by
//! the flat cloth itself). Each particle of a pair closer than `t` moves half of `t − d`
//! away along the line between them (all of it when the other is pinned), and the move
//! is added to its velocity (`Δx/dt`, as the strain limit and XPBD do): the two pushes of
//! a pair are equal and opposite (the fixed-point sum truncates both alike), so the
//! response is internal and keeps the cloth's momentum. (Dropping each particle's own
//! velocity into its contact, as the response did before, is not symmetric: one of two
//! particles meeting loses its approach, the other keeps its own, and a heap on a
//! frictionless floor walked sideways at 0.2 m/s.) Pushes out of an overlap that the
//! substep's own motion made cancel that motion; an older overlap leaves at up to
//! `(t − d)/(2 dt)`. This keeps particles apart, not triangles: two
//! sheets whose particles are farther apart than the thickness can pass between each
//! other's particles, and an edge can cross an edge, when the cloth is coarse next to its
//! thickness (spacing > t·√2) or moves more than the thickness in one substep.
//!
//! The pushes are summed in fixed point ([`UNITS`] per thickness, truncated, at most
//! [`MAX_CONTACTS`] of them): integers add up to the same bits in any order, so the
//! scatter's atomic order needs no sort and every backend computes the CPU's sum.
//!
//! The hash lives in integrator scratch buffers that are dead by then: aux2 holds one
//! `u32` word per bucket (count, then end, then start); aux3 the blocks' totals (`.z` of
//! the first table_size / WORKGROUP elements, as `u32`); aux4 per slot the position of
//! the particle there and its slot word (grid coordinates, row tag, pinned) as the bits
//! of `.w`: the response reads one element per entry, in order.

use clothlab_core::grid::{Rows, SpringSlot, V4};
use clothlab_core::layout::WORKGROUP;
use clothlab_core::step_params::StepParams;

use super::{Exec, for_each2};

/// The cell-to-bucket rule of every contact's broad phase ([`clothlab_core::broad`]): a row of
/// cells in x is a run of consecutive buckets.
pub use clothlab_core::broad::{PRIMES, bucket, row_start};
/// Cell coordinates are clamped to ±1e9 before they are converted to integers.
const CELL_LIMIT: f32 = 1e9;
/// Buckets per particle, about (the table is this times the largest power of two not
/// above the particle count): few foreign cells share a bucket a probe reads.
pub const TABLE_FACTOR: u32 = 4;
/// Fixed-point units of a push per thickness (a push is at most `t`: 2¹⁶ units).
pub const UNITS: f32 = clothlab_core::tables::CONTACT_UNITS;
/// Contacts a particle's pushes are summed for at most: below 2³¹ / 2¹⁶, so the sum never
/// overflows. A particle with more (a pile far denser than cloth lies) is not pushed:
/// decided by the count, which is the same in any order.
pub const MAX_CONTACTS: u32 = 32767;
/// How far the response looks, in cells (thicknesses): a little more than one, so that
/// rounding never drops a cell that holds a contact (the distance decides).
const REACH: f32 = 1.001;

/// Word views of the hash's buffers.
fn words(v: &[V4]) -> &[u32] {
    bytemuck::cast_slice(v)
}

fn words_mut(v: &mut [V4]) -> &mut [u32] {
    bytemuck::cast_slice_mut(v)
}

/// `floor(v)` without libm's call (baseline x86-64 has no rounding instruction): the
/// truncation, one less below zero where it was not exact. Equal to floor for every
/// value in ±1e9.
#[inline]
fn floor_i32(v: f32) -> i32 {
    let t = v as i32;
    t - i32::from((t as f32) > v)
}

/// A point in cell units: the position times `1/t` (computed on the host: a product is
/// rounded alike everywhere, a quotient is not), clamped to ±1e9.
#[inline]
fn scaled(x: &V4, inv_cell: f32) -> [f32; 3] {
    std::array::from_fn(|k| (x[k] * inv_cell).clamp(-CELL_LIMIT, CELL_LIMIT))
}

/// The cell of a point: `floor(x / t)` per axis.
#[inline]
pub fn cell_of(x: &V4, inv_cell: f32) -> [i32; 3] {
    scaled(x, inv_cell).map(floor_i32)
}

/// Buckets of the hash over `len` particles: [`TABLE_FACTOR`] times the largest power of
/// two not above it (a power of two: the bucket is a mask, not a division; at most four
/// words a particle: aux2 holds them).
#[inline]
pub fn table_size(len: usize) -> u32 {
    let len = len.max(1) as u32;
    TABLE_FACTOR << (31 - len.leading_zeros())
}

/// The blocks of [`WORKGROUP`] buckets the scan sums separately.
#[inline]
pub fn hash_blocks(len: usize) -> u32 {
    table_size(len).div_ceil(WORKGROUP)
}

/// Bits of a grid coordinate in a slot's word (n ≤ 4096).
const COORD_BITS: u32 = 12;
const COORD_MASK: u32 = (1 << COORD_BITS) - 1;

/// A cell's row tag: its y modulo 8 and z modulo 16, in bits 24 to 30 of a slot's word.
/// An entry whose tag is not its row's (another row hashed to the same bucket) is refused
/// before its distance is computed; one in 128 of those slip through, and the distance
/// refuses them.
#[inline]
pub fn row_tag(y: i32, z: i32) -> u32 {
    ((y & 7) | (z & 15) << 3) as u32
}

/// The top bit of a slot's word: the particle is pinned.
const PINNED: u32 = 1 << 31;

/// What a slot holds for particle `i` of an `n`-wide grid in cell `c` (besides its
/// position): its grid coordinates, its row's tag and whether it is pinned (`pinned`),
/// `i | j << 12 | tag << 24 | pinned << 31` — enough to refuse a grid neighbour or a
/// foreign row by the word alone. A mesh (`n = 0`) has no coordinates: its particle's
/// index in their 24 bits (`tables::SELF_COLLISION_MAX_PARTICLES`), its neighbours refused from the
/// spring table.
#[inline]
pub fn slot_word(i: u32, n: u32, c: [i32; 3], pinned: bool) -> u32 {
    let id = if n == 0 { i & INDEX_MASK } else { (i % n) | (i / n) << COORD_BITS };
    id | row_tag(c[1], c[2]) << (2 * COORD_BITS) | if pinned { PINNED } else { 0 }
}

/// The mobility (`pos.w`, the relative inverse mass) of the particle whose slot's word is
/// `w`: 0 pinned; a grid's free particles 1 (read from the word alone), a mesh's its own
/// (read from `pos` for a contact only).
#[inline]
pub fn other_mobility(w: u32, mesh: bool, pos: &[V4]) -> f32 {
    if w & PINNED != 0 {
        0.0
    } else if mesh {
        pos[slot_index(w) as usize][3]
    } else {
        1.0
    }
}

/// A contact's share of its push, the same number at both ends: `1 / (wᵢ + wⱼ)` (at most 1,
/// so that a push stays within the fixed point's room), each end then moved by its own
/// mobility times it — by inverse mass, so that the pair's momentum stays whatever the
/// two particles weigh (a mesh's vary). On a grid 0.5 between free particles and 1 against
/// a pinned one, the shares it always had.
#[inline]
pub fn pair_share(wi: f32, wj: f32) -> f32 {
    (1.0 / (wi + wj)).min(1.0)
}

/// A mesh's particle index in a slot's word: its low 24 bits.
const INDEX_MASK: u32 = (1 << (2 * COORD_BITS)) - 1;

const _: () = assert!(clothlab_core::tables::SELF_COLLISION_MAX_PARTICLES == 1 << (2 * COORD_BITS));

/// A mesh's particle index in a slot's word.
#[inline]
pub fn slot_index(w: u32) -> u32 {
    w & INDEX_MASK
}

/// Whether particles `a` and `b` of a mesh may collide: `b` is not among `a`'s springs
/// (its edges and the springs across them, in `table`, the gather table). The rest
/// distance is checked once for the whole mesh instead (`MeshTables::closest_unsprung`
/// against twice the thickness, when the parameters are checked).
#[inline]
pub fn mesh_candidates(table: &Rows<SpringSlot>, a: usize, b: usize) -> bool {
    a != b && !table.row(a).iter().any(|s| s.other() == Some(b))
}

/// The grid coordinates `(i, j)` of a slot's word.
#[inline]
pub fn slot_coords(w: u32) -> (u32, u32) {
    (w & COORD_MASK, w >> COORD_BITS & COORD_MASK)
}

/// The row tag of a slot's word.
#[inline]
pub fn slot_tag(w: u32) -> u32 {
    w >> (2 * COORD_BITS) & 127
}

/// `1 / self_thickness`, the cells' inverse size (computed once, in [`StepParams::new`]).
#[inline]
pub fn inv_cell(p: &StepParams) -> f32 {
    p.inv_cell
}

/// Step 1: the buckets' counts into `cells`, and their blocks' (of [`WORKGROUP`]
/// buckets) into `totals[g].z` (both cleared before).
pub fn hash_count(p: &StepParams, pos: &[V4], cells: &mut [V4], totals: &mut [V4]) {
    let (size, inv) = (table_size(pos.len()), inv_cell(p));
    let (cells, totals) = (words_mut(cells), words_mut(totals));
    for x in pos {
        let b = bucket(cell_of(x, inv), size) as usize;
        cells[b] = cells[b].wrapping_add(1);
        let g = 4 * (b / WORKGROUP as usize) + 2;
        totals[g] = totals[g].wrapping_add(1);
    }
}

/// Step 2b: within each block of [`WORKGROUP`] buckets, the inclusive prefix of the
/// counts in place from the block's offset (`totals[g].z` after step 2a): each bucket's
/// end in the whole array.
pub fn hash_scan_blocks(cells: &mut [V4], totals: &[V4]) {
    let size = table_size(totals.len()) as usize;
    let (cells, totals) = (words_mut(cells), words(totals));
    let w = WORKGROUP as usize;
    for (g, block) in cells[..size].chunks_mut(w).enumerate() {
        let mut acc = totals[4 * g + 2];
        for c in block {
            acc = acc.wrapping_add(*c);
            *c = acc;
        }
    }
}

/// Step 2a: the exclusive prefix of the blocks' totals, in place (`totals[g].z`): each
/// block's offset.
pub fn hash_scan_top(totals: &mut [V4]) {
    let blocks = hash_blocks(totals.len()) as usize;
    let totals = words_mut(totals);
    let mut acc = 0u32;
    for g in 0..blocks {
        let total = totals[4 * g + 2];
        totals[4 * g + 2] = acc;
        acc = acc.wrapping_add(total);
    }
}

/// Step 3: every particle's position and [`slot_word`] (as the bits of `.w`; its bucket
/// and word computed again from its position, which is cheaper than storing them in step
/// 1 and loading them here) into the slot of `slots` before its bucket's end (the
/// particles of a bucket in index order here, in any order on a GPU), which moves the
/// bucket's word down to its start. Slots out of range (never after [`hash_count`] and the
/// scans) are skipped.
///
/// With Coulomb friction ([`StepParams::coulomb`]) every particle's velocity is also
/// copied into `vel_copy` (by index): the response reads its contacts' velocities there,
/// since it writes `vel` in place.
pub fn hash_scatter(p: &StepParams, pos: &[V4], vel: &[V4], cells: &mut [V4], slots: &mut [V4], vel_copy: &mut [V4]) {
    if p.coulomb() {
        vel_copy[..vel.len()].copy_from_slice(vel);
    }
    let (size, inv) = (table_size(pos.len()), inv_cell(p));
    let cells = words_mut(cells);
    for (i, x) in pos.iter().enumerate().rev() {
        let c = cell_of(x, inv);
        let cell = &mut cells[bucket(c, size) as usize];
        let slot = cell.wrapping_sub(1);
        *cell = slot;
        if let Some(s) = slots.get_mut(slot as usize) {
            *s = [x[0], x[1], x[2], f32::from_bits(slot_word(i as u32, p.n, c, x[3] == 0.0))];
        }
    }
}

/// The hash's buffers among the integrators' scratch buffers (`aux`, [`super::AUX`] of
/// them): aux2 (cells), aux3 (the blocks' totals), aux4 (slots), and aux0, the
/// velocities' copy that Coulomb friction between particles reads ([`hash_scatter`]).
pub struct HashBuffers<'a> {
    /// aux2: a word per bucket.
    pub cells: &'a mut [V4],
    /// aux3: the blocks' totals.
    pub totals: &'a mut [V4],
    /// aux4: the slots.
    pub slots: &'a mut [V4],
    /// aux0: the velocities before the response (Coulomb friction only).
    pub vel_copy: &'a mut [V4],
}

/// [`HashBuffers`] in `aux`.
pub fn hash_buffers(aux: &mut [Vec<V4>]) -> HashBuffers<'_> {
    let [vel_copy, _, cells, totals, slots, ..] = aux else { panic!("the {} integrator scratch buffers", super::AUX) };
    HashBuffers { cells, totals, slots, vel_copy }
}

/// Steps 1 to 3: the hash of `pos` in `h` (one element per particle each buffer).
pub fn build_hash(p: &StepParams, pos: &[V4], vel: &[V4], h: &mut HashBuffers) {
    let HashBuffers { cells, totals, slots, vel_copy } = h;
    cells.iter_mut().for_each(|c| *c = [0.0; 4]);
    totals[..hash_blocks(pos.len()) as usize].iter_mut().for_each(|c| *c = [0.0; 4]);
    hash_count(p, pos, cells, totals);
    hash_scan_top(totals);
    hash_scan_blocks(cells, totals);
    hash_scatter(p, pos, vel, cells, slots, vel_copy);
}

/// The slots `[start, end)` of bucket `b` after the scatter, clamped to the `np` slots
/// (`cells` as words): a row of one cell.
#[inline]
pub fn bucket_range(cells: &[u32], b: u32, size: u32, np: u32) -> (u32, u32) {
    row_ranges(cells, Row { first: b, len: 1, tag: 0 }, size, np)[0]
}

/// The slots of a row's buckets: one range, or two where its buckets wrap around the
/// table's end (the second empty otherwise).
#[inline]
pub fn row_ranges(cells: &[u32], row: Row, size: u32, np: u32) -> [(u32, u32); 2] {
    let stop = row.first + row.len;
    let start = cells[row.first as usize].min(np);
    if stop <= size {
        let end = if stop < size { cells[stop as usize] } else { np };
        [(start, end.clamp(start, np)), (0, 0)]
    } else {
        let wrapped = cells[0].min(np);
        [(start, np), (wrapped, cells[(stop - size) as usize].clamp(wrapped, np))]
    }
}

/// The words of a hash buffer (aux2, aux3), for probes and tests.
pub fn hash_words(v: &[V4]) -> &[u32] {
    words(v)
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

/// The squared distance (in cells) from a point at fraction `f` of its cell to the
/// neighbour cell at offset `d` (−1, 0, 1) along one axis.
#[inline]
fn gap2(f: f32, d: i32) -> f32 {
    match d {
        0 => 0.0,
        d if d < 0 => f * f,
        _ => (1.0 - f) * (1.0 - f),
    }
}

/// One row of cells the response reads: its first bucket and how many (1 to 3); their
/// particles are one range of the sorted array, or two where the buckets wrap around.
#[derive(Clone, Copy, Default)]
pub struct Row {
    /// The bucket of its first cell.
    pub first: u32,
    /// Its cells (and buckets).
    pub len: u32,
    /// Its [`row_tag`].
    pub tag: u32,
}

/// A point's cell and its fraction of the way across it, per axis (cell units).
#[inline]
pub fn cell_and_fraction(x: &V4, inv: f32) -> ([i32; 3], [f32; 3]) {
    let v = scaled(x, inv);
    let c = v.map(floor_i32);
    (c, std::array::from_fn(|a| v[a] - c[a] as f32))
}

/// The cells in x of row `(y, z)` that the sphere of radius `REACH` around a point in
/// cell `c` at fraction `f` reaches — those whose squared distance from the point, the
/// sum of its squared gaps per axis, is below `REACH²` — as `(lo, hi)`; `None` where it
/// reaches none of them (the GPU kernel's `reached_cells`, row by row: no square root).
#[inline]
pub fn reach(c: [i32; 3], f: [f32; 3], y: i32, z: i32) -> Option<(i32, i32)> {
    let (dy, dz) = (y.wrapping_sub(c[1]), z.wrapping_sub(c[2]));
    if dy.abs() > 1 || dz.abs() > 1 {
        return None;
    }
    let (gyz, r2) = (gap2(f[2], dz) + gap2(f[1], dy), REACH * REACH);
    if gyz >= r2 {
        return None;
    }
    let (below, above) = (gap2(f[0], -1), gap2(f[0], 1));
    Some((c[0].wrapping_sub(i32::from(gyz + below < r2)), c[0].wrapping_add(i32::from(gyz + above < r2))))
}

/// The rows of cells (in x) within `REACH` of a point, in the response's order (z, then
/// y, from −1 to 1): each as its first bucket and length; rows the sphere misses are
/// left out. Returns how many.
pub fn rows_around(x: &V4, inv: f32, size: u32, rows: &mut [Row; 9]) -> usize {
    let (c, f) = cell_and_fraction(x, inv);
    let mut count = 0;
    for dz in -1..=1 {
        for dy in -1..=1 {
            let (y, z) = (c[1].wrapping_add(dy), c[2].wrapping_add(dz));
            let Some((lo, hi)) = reach(c, f, y, z) else { continue };
            let first = bucket([lo, y, z], size);
            rows[count] = Row { first, len: hi.wrapping_sub(lo) as u32 + 1, tag: row_tag(y, z) };
            count += 1;
        }
    }
    count
}

/// The index of the particle whose slot word is `w`: a grid's `j·n + i` from its
/// coordinates, a mesh's (`n = 0`) from the word's low bits.
#[inline]
pub fn slot_particle(w: u32, n: u32) -> usize {
    if n == 0 {
        slot_index(w) as usize
    } else {
        let (i, j) = slot_coords(w);
        (j * n + i) as usize
    }
}

/// The part of a relative tangential velocity that one sticking contact removes. The
/// contacts of a particle are summed (Jacobi), not solved one after another: a particle
/// of a sheet lying on another touches up to four of its particles, and four contacts that
/// each removed all of it would reverse it threefold (against a held sheet) — a quarter
/// each removes at most all of it, so a stuck pair's slip decays without overshooting.
pub const STICK: f32 = 0.25;

/// Coulomb friction between two particles in contact (`e = xᵢ − xⱼ`, `d2 = |e|²`, the
/// pair pushed `sep = t − d` apart this substep, `w = vᵢ − vⱼ` their relative velocity
/// before the response): the relative tangential velocity the contact removes. The push
/// is the pair's normal impulse, `Δv_n = sep / dt`; a slip `|v_t| ≤ μs·Δv_n` sticks
/// ([`STICK`] of it removed), a faster one loses `μk·Δv_n` (at most [`STICK`] of it). Odd
/// in `(e, w)` bit for bit (every product and sum of negated inputs is the negated
/// result), so the pair's two ends remove equal and opposite amounts: the response keeps
/// the cloths' momentum. The shaders' `pair_friction`, in the same order.
#[inline]
pub fn pair_friction(p: &StepParams, e: [f32; 3], d2: f32, sep: f32, w: [f32; 3]) -> [f32; 3] {
    let k = (w[0] * e[0] + w[1] * e[1] + w[2] * e[2]) / d2;
    let vt: [f32; 3] = std::array::from_fn(|a| w[a] - k * e[a]);
    let vtl = (vt[0] * vt[0] + vt[1] * vt[1] + vt[2] * vt[2]).sqrt();
    let dvn = sep * (1.0 / p.dt);
    let keep = if vtl > p.mu_static() * dvn { STICK.min(p.mu_kinetic() * dvn / vtl) } else { STICK };
    vt.map(|v| v * keep)
}

/// Fixed-point units of friction per `μs·t/dt` (a contact's removal, times its share, is
/// at most that: [`pair_friction`]), so that a sum of [`MAX_CONTACTS`] never overflows.
#[inline]
fn friction_scale(p: &StepParams) -> f32 {
    UNITS * p.inv_cell * p.dt / p.mu_static()
}

/// Particle `i`'s new position and velocity: pushed out of every candidate
/// closer than the thickness, the push added to its velocity as motion (`Δx/dt`). `table` (the gather
/// table, `None` for a grid) refuses a mesh's neighbours; a grid's are refused by their
/// coordinates. With Coulomb friction ([`StepParams::coulomb`]) each contact also removes
/// the pair's tangential slip ([`pair_friction`], the contact's velocity read from
/// `vel_copy`), summed in fixed point as the pushes are; the position moves back by the
/// velocity friction removed times `dt`, as at a collider (no creep).
#[allow(clippy::too_many_arguments)] // the twin of one kernel's particle: its buffers
pub fn self_collide_at(
    p: &StepParams,
    i: usize,
    pos: &[V4],
    vel: V4,
    cells: &[V4],
    slots: &[V4],
    vel_copy: &[V4],
    table: Option<&Rows<SpringSlot>>,
) -> (V4, V4) {
    if p.coulomb() {
        response::<true>(p, i, pos, vel, cells, slots, vel_copy, table)
    } else {
        response::<false>(p, i, pos, vel, cells, slots, vel_copy, table)
    }
}

/// [`self_collide_at`] with friction (`COULOMB`) or without: two functions, so that the
/// frictionless one carries no friction code in its contact loop (as the GPU's
/// `self_collide` and `self_collide_friction` are two kernels; measured 6–9 % of the
/// response on cpu-par with the branch in the loop).
#[allow(clippy::too_many_arguments)] // self_collide_at's
#[inline(always)]
fn response<const COULOMB: bool>(
    p: &StepParams,
    i: usize,
    pos: &[V4],
    vel: V4,
    cells: &[V4],
    slots: &[V4],
    vel_copy: &[V4],
    table: Option<&Rows<SpringSlot>>,
) -> (V4, V4) {
    let x4 = pos[i];
    if x4[3] == 0.0 || i as i32 == p.grab_index {
        return (x4, vel);
    }
    let t = p.self_thickness;
    let np = pos.len() as u32;
    let size = table_size(pos.len());
    let cells = words(cells);
    let inv = inv_cell(p);
    let mesh = p.n == 0;
    let n = p.n.max(1);
    let me = ((i as u32 % n) as i32, (i as u32 / n) as i32);
    let mut rows = [Row::default(); 9];
    let count = rows_around(&x4, inv, size, &mut rows);
    // Fixed point: UNITS per thickness (scale = UNITS / t, a product by a power of two).
    let scale = UNITS * inv;
    let mut sum = [0i32; 3];
    let mut contacts = 0u32;
    let coulomb = COULOMB;
    let fscale = if coulomb { friction_scale(p) } else { 0.0 };
    let mut rub = [0i32; 3];
    for row in &rows[..count] {
        for (start, end) in row_ranges(cells, *row, size, np) {
            for s in start..end {
                // Foreign rows and grid neighbours refused by the slot's word.
                let y4 = slots[s as usize];
                let w = y4[3].to_bits();
                if slot_tag(w) != row.tag {
                    continue;
                }
                let (qi, qj) = slot_coords(w);
                if !mesh && !candidate_coords(p, me, (qi as i32, qj as i32)) {
                    continue;
                }
                let e = [x4[0] - y4[0], x4[1] - y4[1], x4[2] - y4[2]];
                let d2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
                if d2 >= t * t || d2 < 1e-12 {
                    continue;
                }
                // A mesh's neighbours from the table, only for what is close (rare).
                if let Some(table) = table.filter(|_| mesh)
                    && !mesh_candidates(table, i, slot_index(w) as usize)
                {
                    continue;
                }
                contacts += 1;
                let d = d2.sqrt();
                let share = pair_share(x4[3], other_mobility(w, mesh, pos));
                let push = (t - d) / d * share * scale;
                for a in 0..3 {
                    sum[a] = sum[a].wrapping_add((e[a] * push) as i32);
                }
                if coulomb {
                    let vj = vel_copy[slot_particle(w, p.n)];
                    let rel = [vel[0] - vj[0], vel[1] - vj[1], vel[2] - vj[2]];
                    let r = pair_friction(p, e, d2, t - d, rel);
                    let f = share * fscale;
                    for a in 0..3 {
                        rub[a] = rub[a].wrapping_add((r[a] * f) as i32);
                    }
                }
            }
        }
    }
    if contacts > MAX_CONTACTS {
        return (x4, vel);
    }
    // The pair's share times this particle's mobility: its part of the push by inverse
    // mass (×1 on a grid).
    let unit = t * (1.0 / UNITS);
    let delta = sum.map(|v| v as f32 * unit * x4[3]);
    let dd = delta[0] * delta[0] + delta[1] * delta[1] + delta[2] * delta[2];
    if coulomb {
        // Friction's velocity, by inverse mass as the push.
        let funit = p.mu_static() * t * (1.0 / UNITS) * (1.0 / p.dt);
        let fr = rub.map(|v| v as f32 * funit * x4[3]);
        if dd == 0.0 && fr == [0.0; 3] {
            return (x4, vel);
        }
        let x: [f32; 3] = std::array::from_fn(|a| x4[a] + (delta[a] - fr[a] * p.dt));
        let u: [f32; 3] = std::array::from_fn(|a| vel[a] + delta[a] * (1.0 / p.dt) - fr[a]);
        return ([x[0], x[1], x[2], x4[3]], [u[0], u[1], u[2], vel[3]]);
    }
    if dd == 0.0 {
        return (x4, vel);
    }
    let x = [x4[0] + delta[0], x4[1] + delta[1], x4[2] + delta[2]];
    // The push is motion (as the strain limit's is): v += Δx / dt, from the push itself
    // (a pair's two are one fixed-point value with two signs, so are their velocity
    // changes; and a shader compiler may fold `(x + Δx) − x` to Δx, so that is what both
    // compute).
    let inv_dt = 1.0 / p.dt;
    let u: [f32; 3] = std::array::from_fn(|a| vel[a] + delta[a] * inv_dt);
    ([x[0], x[1], x[2], x4[3]], [u[0], u[1], u[2], vel[3]])
}

/// Step 4: every particle pushed out of its close candidates (from `slots`) into
/// `pos_out`, its `vel` updated in place (each element read and written only by its own
/// particle).
#[allow(clippy::too_many_arguments)] // the twin of one kernel: its buffers, one each
pub fn self_collide(
    exec: Exec,
    p: &StepParams,
    pos: &[V4],
    vel: &mut [V4],
    cells: &[V4],
    slots: &[V4],
    vel_copy: &[V4],
    table: Option<&Rows<SpringSlot>>,
    pos_out: &mut [V4],
) {
    if p.coulomb() {
        sweep::<true>(exec, p, pos, vel, cells, slots, vel_copy, table, pos_out)
    } else {
        sweep::<false>(exec, p, pos, vel, cells, slots, vel_copy, table, pos_out)
    }
}

/// [`self_collide`] over every particle with [`response`]'s `COULOMB` chosen once (its own
/// loop per choice: a function pointer chosen once instead, one loop, cost the frictionless
/// response 3 % on cpu-par — 1668–1699 against 1624–1648 µs, the heap at n = 128).
#[allow(clippy::too_many_arguments)] // self_collide's
fn sweep<const COULOMB: bool>(
    exec: Exec,
    p: &StepParams,
    pos: &[V4],
    vel: &mut [V4],
    cells: &[V4],
    slots: &[V4],
    vel_copy: &[V4],
    table: Option<&Rows<SpringSlot>>,
    pos_out: &mut [V4],
) {
    for_each2(exec, pos_out, vel, |i, o, q| {
        let (x, xp) = response::<COULOMB>(p, i, pos, *q, cells, slots, vel_copy, table);
        *o = x;
        *q = xp;
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use clothlab_core::params::SimParams;
    use clothlab_core::scene::Scene;

    fn params(n: u32, t: f32) -> StepParams {
        let sp = SimParams {
            self_collision: clothlab_core::params::SelfCollision::Particles,
            self_thickness: t,
            ..SimParams::default()
        };
        StepParams::new(&sp, &Scene::with_n(n), None)
    }

    /// A deterministic scatter of points in `[0, side)³` (a small LCG).
    fn cloud(np: usize, side: f32, seed: u32) -> Vec<V4> {
        let mut s = seed;
        let mut next = move || {
            s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (s >> 8) as f32 / (1 << 24) as f32
        };
        // Every fifth pinned (inverse mass 0): it pushes the others all the way.
        (0..np).map(|i| [next() * side, next() * side, next() * side, if i % 5 == 0 { 0.0 } else { 1.0 }]).collect()
    }

    #[test]
    fn the_hash_lists_every_particle_once_in_its_bucket_in_index_order() {
        // 289 particles over a few cells, so that buckets hold several.
        let n = 17;
        let p = params(n, 0.05);
        let np = (n * n) as usize;
        let pos: Vec<V4> =
            (0..np).map(|i| [(i % 7) as f32 * 0.031, (i % 5) as f32 * 0.043, (i % 3) as f32 * 0.07, 1.0]).collect();
        let mut aux = vec![vec![[0.0; 4]; np]; super::super::AUX];
        let mut h = hash_buffers(&mut aux);
        build_hash(&p, &pos, &pos, &mut h);
        let (cells, slots) = (&*h.cells, &*h.slots);
        let size = table_size(np);
        assert_eq!(size, 1024);
        let cw = words(cells);
        let mut listed = vec![0; np];
        let mut tiled = 0;
        for b in 0..size {
            let (start, end) = bucket_range(cw, b, size, np as u32);
            assert_eq!(start, tiled, "bucket {b} starts where the one before ends");
            tiled = end;
            let ids: Vec<u32> = (start..end)
                .map(|s| {
                    let (i, j) = slot_coords(slots[s as usize][3].to_bits());
                    let q = j * n + i;
                    assert_eq!(slots[s as usize][..3], pos[q as usize][..3], "slot {s} holds particle {q}'s position");
                    q
                })
                .collect();
            assert!(ids.windows(2).all(|w| w[0] < w[1]), "bucket {b}: {ids:?} not in index order");
            for &q in &ids {
                assert_eq!(bucket(cell_of(&pos[q as usize], inv_cell(&p)), size), b);
                listed[q as usize] += 1;
            }
        }
        assert_eq!(tiled as usize, np, "the ranges tile the array");
        assert!(listed.iter().all(|&c| c == 1), "every particle listed exactly once");
    }

    #[test]
    fn neighbours_in_x_are_consecutive_buckets() {
        let size = table_size(1000);
        for c in [[0, 0, 0], [-5, 3, 7], [1_000_000, -2, 9]] {
            let b = bucket(c, size);
            assert_eq!(bucket([c[0] + 1, c[1], c[2]], size), (b + 1) & (size - 1));
            assert_eq!(bucket([c[0] - 1, c[1], c[2]], size), b.wrapping_sub(1) & (size - 1));
        }
    }

    /// The response of particle `i` by brute force: the same fixed-point pushes from every
    /// candidate closer than `t`, found without the hash.
    fn brute_force_push(p: &StepParams, i: usize, pos: &[V4]) -> [i32; 3] {
        let (t, scale) = (p.self_thickness, UNITS * p.inv_cell);
        let mut sum = [0i32; 3];
        for (q, y4) in pos.iter().enumerate() {
            if !candidates(p, i as u32, q as u32) {
                continue;
            }
            let e = [pos[i][0] - y4[0], pos[i][1] - y4[1], pos[i][2] - y4[2]];
            let d2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
            if d2 >= t * t || d2 < 1e-12 {
                continue;
            }
            let d = d2.sqrt();
            let s = (t - d) / d * if y4[3] == 0.0 { 1.0 } else { 0.5 } * scale;
            for a in 0..3 {
                sum[a] = sum[a].wrapping_add((e[a] * s) as i32);
            }
        }
        sum
    }

    #[test]
    fn the_rows_find_every_contact_that_brute_force_finds() {
        // 1024 particles in a cube four thicknesses wide (about 16 a cell, many contacts
        // each, every offset to a cell's faces; a fifth pinned): the response through the
        // hash moves each free particle (four fifths) by exactly the brute-force sum of its
        // pushes (fixed point: any order gives the same bits), so no row or cell it trims
        // held a contact, and a pinned one pushes all the way.
        let (n, t) = (32, 0.01);
        let p = params(n, t);
        let np = (n * n) as usize;
        for seed in [1, 2, 3] {
            let pos = cloud(np, 4.0 * t, seed);
            let mut aux = vec![vec![[0.0; 4]; np]; super::super::AUX];
            let mut h = hash_buffers(&mut aux);
            build_hash(&p, &pos, &pos, &mut h);
            let mut pushed = 0;
            for i in 0..np {
                let (x, _) = self_collide_at(&p, i, &pos, pos[i], h.cells, h.slots, h.vel_copy, None);
                if pos[i][3] == 0.0 {
                    assert_eq!(x, pos[i], "a pinned particle stays");
                    continue;
                }
                let want = brute_force_push(&p, i, &pos).map(|v| v as f32 * (t * (1.0 / UNITS)));
                let got = [x[0] - pos[i][0], x[1] - pos[i][1], x[2] - pos[i][2]];
                let exact: [f32; 3] = std::array::from_fn(|a| (pos[i][a] + want[a]) - pos[i][a]);
                assert_eq!(got, exact, "seed {seed} particle {i}");
                pushed += usize::from(want != [0.0; 3]);
            }
            assert!(pushed > np * 7 / 10, "seed {seed}: only {pushed} of {np} particles had contacts");
        }
    }

    #[test]
    fn two_particles_closer_than_the_thickness_end_the_thickness_apart() {
        // Two far-apart particles of the grid (not neighbours) 0.6 t apart: each moves
        // 0.2 t away, and that move is added to its velocity (Δx/dt), so the pair's
        // momentum stays. Within two fixed-point units (t / 65536 each: a push is
        // truncated to them).
        let n = 16;
        let t = 0.02;
        let unit = t / UNITS;
        let p = params(n, t);
        let np = (n * n) as usize;
        let mut pos: Vec<V4> = (0..np).map(|i| [i as f32 * 10.0, 5.0, 0.0, 1.0]).collect();
        let (a, b) = (0usize, np - 1);
        pos[a] = [0.3, 1.0, 0.0, 1.0];
        pos[b] = [0.3 + 0.6 * t, 1.0, 0.0, 1.0];
        let mut vel = vec![[0.0f32; 4]; np];
        vel[a][0] = 0.06; // a moves towards b at 6 cm/s
        let mut aux = vec![vec![[0.0; 4]; np]; super::super::AUX];
        let mut h = hash_buffers(&mut aux);
        build_hash(&p, &pos, &vel, &mut h);
        let mut out = pos.clone();
        self_collide(Exec::Serial, &p, &pos, &mut vel, h.cells, h.slots, h.vel_copy, None, &mut out);
        let gap = out[b][0] - out[a][0];
        assert!((gap - t).abs() < 2.0 * unit, "gap {gap}, thickness {t}");
        assert!((out[a][0] - (0.3 - 0.2 * t)).abs() < 2.0 * unit);
        // Each gained its push over dt (0.2 t / dt = 0.384 m/s apart), within two units
        // over dt (2.3e-4 m/s); the pair's momentum is a's 0.06 m/s to rounding (the two
        // pushes are one truncated value with two signs; each lands on a position rounded
        // to half an ulp of 0.3 m: 3e-8 m, 2.9e-5 m/s).
        let push = 0.2 * t / p.dt;
        assert!((vel[b][0] - push).abs() < 2.0 * unit / p.dt, "b moves at {} m/s, want {push}", vel[b][0]);
        assert!((vel[a][0] - (0.06 - push)).abs() < 2.0 * unit / p.dt, "a moves at {} m/s", vel[a][0]);
        assert!((vel[a][0] + vel[b][0] - 0.06).abs() < 6e-5, "momentum {} m/s", vel[a][0] + vel[b][0]);
        assert_eq!([vel[a][1], vel[a][2], vel[b][1], vel[b][2]], [0.0; 4]);
        // Everyone else is untouched.
        assert_eq!(out[1], pos[1]);
    }

    #[test]
    fn friction_between_two_particles_removes_a_quarter_of_a_sticking_slip_and_mu_k_of_a_sliding_one() {
        // Two far-apart particles of the grid 0.8 t apart along y, slipping past each other
        // along x, with μs 0.5, μk 0.3 (t = 2.2 cm, dt = 1/960 s): the pair is pushed 0.2 t
        // apart, a normal velocity Δv_n = 0.2 t / dt = 4.22 m/s. A slip of 1 m/s ≤ μs Δv_n
        // sticks: STICK of it (0.25 m/s) is removed, each end (share ½) 0.125 m/s in
        // opposite directions (the pair's momentum stays). A slip of 10 m/s slides: μk Δv_n
        // = 1.27 m/s is removed, 0.633 m/s each end. Within two fixed-point units of
        // friction (μs t / dt / 65536 = 1.6e-4 m/s).
        let (n, t) = (16, 0.022);
        let sp = SimParams {
            self_collision: clothlab_core::params::SelfCollision::Particles,
            self_thickness: t,
            static_friction: 0.5,
            kinetic_friction: 0.3,
            ..SimParams::default()
        };
        let p = StepParams::new(&sp, &Scene::with_n(n), None);
        let np = (n * n) as usize;
        let mut pos: Vec<V4> = (0..np).map(|i| [i as f32 * 10.0, 5.0, 0.0, 1.0]).collect();
        let (a, b) = (0usize, np - 1);
        pos[a] = [0.3, 1.0, 0.0, 1.0];
        pos[b] = [0.3, 1.0 + 0.8 * t, 0.0, 1.0];
        let unit = 0.5 * t / p.dt / UNITS;
        for (slip, removed) in [(1.0f32, 0.25f32), (10.0, 0.3 * 0.2 * t / p.dt)] {
            let mut vel = vec![[0.0f32; 4]; np];
            vel[b][0] = slip;
            let mut aux = vec![vec![[0.0; 4]; np]; super::super::AUX];
            let mut h = hash_buffers(&mut aux);
            build_hash(&p, &pos, &vel, &mut h);
            let mut out = pos.clone();
            self_collide(Exec::Serial, &p, &pos, &mut vel, h.cells, h.slots, h.vel_copy, None, &mut out);
            let each = removed / 2.0;
            assert!((vel[a][0] - each).abs() < 2.0 * unit, "slip {slip}: a dragged to {} m/s, want {each}", vel[a][0]);
            assert!((vel[b][0] - (slip - each)).abs() < 2.0 * unit, "slip {slip}: b slowed to {} m/s", vel[b][0]);
            assert!((vel[a][0] + vel[b][0] - slip).abs() <= slip * 1e-6, "slip {slip}: the pair's momentum");
            // Moved back by what friction removed times dt (no creep): 0.125 m/s × dt.
            assert!((out[a][0] - (pos[a][0] + each * p.dt)).abs() < 1e-6, "slip {slip}: a at {}", out[a][0]);
        }
    }

    #[test]
    fn cells_are_floors_and_tables_powers_of_two() {
        for v in [-2.5f32, -2.0, -1e-7, 0.0, 1e-7, 0.999_999_9, 1.0, 3.7, -1e12, 1e12] {
            let want = v.floor().clamp(-CELL_LIMIT, CELL_LIMIT) as i32;
            assert_eq!(cell_of(&[v, 0.0, 0.0, 0.0], 1.0)[0], want, "{v}");
        }
        assert_eq!([table_size(1), table_size(4), table_size(289), table_size(4096)], [4, 16, 1024, 16384]);
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
