//! The broad phase of every contact, written once: a uniform grid of cells over points or
//! primitives' boxes, filled by a counting sort into buckets, walked row by row.
//!
//! - **The cell-to-bucket rule** ([`bucket`]): a cell's bucket is its row's start
//!   ([`row_start`], a hash of its y and z) plus its x, so that the cells of a row in x are
//!   consecutive buckets and a query reads a row as one run of memory. The particle
//!   self-collision (`crate::cpu::self_collide`, `hash_*.wgsl`: points in cells one
//!   thickness wide), the contact between triangles (`crate::tri_contact` on the CPU,
//!   `tri_grid_*.wgsl` and their twins in `crate::cpu::tri_contact`: boxes) and the
//!   crossings' count (`crate::crossings`) all list their primitives by it; the WGSL
//!   twin is `shaders/wgsl/shared/cells.wgsl`.
//! - **Boxes** ([`BoxGrid`], [`slot_of`], [`query`]): each box is listed once, in the cell
//!   of its lowest corner; a query looks in the cells from its own box's lowest corner less
//!   the largest listed box's extent to its highest corner, so it meets every box that can
//!   reach it, each once — no box is listed in every cell it covers, and no query has to
//!   tell copies apart. (Listing each box in every cell it covers, each pair met in the
//!   lowest cell the two shared, visited 2–3 times the entries in a pile of sheets and
//!   took three quarters of the contact's time.) A box wider than [`BIG_CELLS`] cells
//!   goes to one more bucket after the grid's, which every query reads whole, instead of
//!   widening every query to it. The CPU's grid ([`BoxGrid`]) and the GPU kernels' twins
//!   walk with the same function ([`query`]) over their own listings ([`Listing`]).

use glam::Vec3;

/// A cell's integer coordinates.
pub type Cell = [i32; 3];

/// The hash's primes for a cell's row (y, z) (Teschner et al. 2003).
pub const PRIMES: [i32; 2] = [689_287_499, 283_923_481];

/// Where a row of cells (y, z) starts among the buckets: `4·((y mod 4) + 4·(z mod 4))`
/// plus 64 times its hash. Two different rows within two cells of each other in y and z
/// differ in the first part (by a multiple of 4 below 64) and so start at least four
/// buckets apart modulo any table of 64 or more: the three cells of one row never share a
/// bucket with those of another row around the same point, and the particle contact's
/// probe needs no check for buckets read twice. (Its tables are 64 or more from n = 4;
/// smaller grids have no pair that may collide. A box query may span more cells: it tells
/// an entry's cell from the others' by the entry's own.)
#[inline]
pub fn row_start(y: i32, z: i32) -> u32 {
    let low = ((y & 3) + 4 * (z & 3)) as u32;
    let hash = (y.wrapping_mul(PRIMES[0]) ^ z.wrapping_mul(PRIMES[1])) as u32;
    4 * low + hash.wrapping_mul(64)
}

/// The bucket of a cell among `size` (a power of two): its row's start plus its x, so
/// that neighbours in x are consecutive buckets.
#[inline]
pub fn bucket(c: Cell, size: u32) -> u32 {
    row_start(c[1], c[2]).wrapping_add(c[0] as u32) & (size - 1)
}

/// Box cell coordinates are clamped to this before they become integers (a far point
/// shares the border cells instead of overflowing).
const CELL_LIMIT: f32 = 1e6;

/// The most cells a box query walks: a query over more (a primitive, or the grid's
/// largest, spanning metres) reads its grid's entries in their order instead.
pub const QUERY_CELLS: u32 = 4096;

/// A box wider than this many cells on some axis is listed apart (the bucket after the
/// grid's: [`slot_of`]).
pub const BIG_CELLS: f32 = 4.0;

/// The cell of a box's corner: `floor(x / cell)` per axis (`x · inv_cell`), clamped.
#[inline]
pub fn cell_of(x: Vec3, inv_cell: f32) -> Cell {
    let c = (x * inv_cell).floor().clamp(Vec3::splat(-CELL_LIMIT), Vec3::splat(CELL_LIMIT));
    [c.x as i32, c.y as i32, c.z as i32]
}

/// Whether the box `[lo, hi]` is listed apart, wider than [`BIG_CELLS`] cells.
#[inline]
pub fn is_big([lo, hi]: [Vec3; 2], cell: f32) -> bool {
    (hi - lo).max_element() > BIG_CELLS * cell
}

/// The bucket a box is listed in among `size` (a power of two) plus one: its lowest
/// corner's cell's, or `size` (the bucket after the grid's) for a box wider than
/// [`BIG_CELLS`] cells; `None` for a box with a corner that is not finite (no query meets
/// it).
#[inline]
pub fn slot_of(b: [Vec3; 2], cell: f32, size: u32) -> Option<u32> {
    if !(b[0].is_finite() && b[1].is_finite()) {
        return None;
    }
    Some(if is_big(b, cell) { size } else { bucket(cell_of(b[0], 1.0 / cell), size) })
}

/// A grid's buckets as a query walks them: the CPU's [`BoxGrid`] or the GPU buffers as
/// the kernels' twins read them.
pub trait Listing {
    /// Bucket `b`'s entries (of `0..=size`: the grid's, then the wide boxes').
    fn range(&self, b: usize) -> std::ops::Range<usize>;
    /// Entry `e`: its primitive and its box.
    fn entry(&self, e: usize) -> (u32, [Vec3; 2]);
    /// Entry `e`'s cell: its box's lowest corner's ([`cell_of`] with `inv_cell`).
    fn cell(&self, e: usize, inv_cell: f32) -> Cell {
        cell_of(self.entry(e).1[0], inv_cell)
    }
}

/// What a query needs to know of a grid besides its entries.
#[derive(Debug, Clone, Copy)]
pub struct Shape {
    /// The cells' width.
    pub cell: f32,
    /// Buckets of the grid (a power of two; one more holds the wide boxes).
    pub size: u32,
    /// The largest extent of a box listed in the grid's buckets, per axis.
    pub extent: Vec3,
    /// A query over more cells than this (on an axis, in a plane or in all) reads every
    /// entry instead ([`QUERY_CELLS`]).
    pub most_cells: u32,
}

/// The cells a query of box `[lo, hi]` grown by `grow` walks: from its lowest corner
/// less the grid's extent to its highest, with a little more than rounding can move a
/// corner (the box test decides).
pub fn query_cells([lo, hi]: [Vec3; 2], grow: f32, s: &Shape) -> [Cell; 2] {
    let inv = 1.0 / s.cell;
    let g = Vec3::splat(grow);
    let slack = Vec3::splat(1e-4 * s.cell + 1e-6 * lo.abs().max(hi.abs()).max_element());
    [cell_of(lo - g - s.extent - slack, inv), cell_of(hi + g + slack, inv)]
}

/// Calls `f` once for every primitive numbered `first` or more whose box meets the box
/// `b` grown by `grow` (closed: boxes that touch meet): the cells of [`query_cells`] row
/// by row (z slowest, x fastest: a row is a run of buckets), an entry taken in the cell
/// of its lowest corner only, then the wide boxes' bucket; a query over more than
/// `most_cells` cells reads every entry in order. A search of pairs among the primitives
/// of one grid passes the one after its own, so that each pair is met once and the others
/// cost an integer test. The GPU's `tri_pairs` walks in this order.
pub fn query(l: &impl Listing, s: &Shape, b: [Vec3; 2], grow: f32, first: u32, mut f: impl FnMut(u32)) {
    let [lo, hi] = b;
    if !(lo.is_finite() && hi.is_finite()) {
        return;
    }
    let inv = 1.0 / s.cell;
    let mut take = |e: usize, cell: Option<Cell>| {
        let (id, eb) = l.entry(e);
        if id >= first && boxes_meet(eb, b, grow) && cell.is_none_or(|c| l.cell(e, inv) == c) {
            f(id);
        }
    };
    let [c0, c1] = query_cells(b, grow, s);
    let span = [0, 1, 2].map(|k| (c1[k] - c0[k] + 1) as u32);
    let most = s.most_cells;
    if span.iter().any(|&n| n > most) || span[0] * span[1] > most || span[0] * span[1] * span[2] > most {
        for e in l.range(0).start..l.range(s.size as usize).end {
            take(e, None);
        }
        return;
    }
    for k in c0[2]..=c1[2] {
        for j in c0[1]..=c1[1] {
            let row = row_start(j, k);
            for i in c0[0]..=c1[0] {
                let bk = row.wrapping_add(i as u32) & (s.size - 1);
                for e in l.range(bk as usize) {
                    take(e, Some([i, j, k]));
                }
            }
        }
    }
    for e in l.range(s.size as usize) {
        take(e, None);
    }
}

/// A primitive in its bucket: its index, its box and its lowest corner's cell (kept: a
/// floor is a call to libm on baseline x86-64).
#[derive(Debug, Clone, Copy)]
struct Entry {
    id: u32,
    cell: Cell,
    lo: Vec3,
    hi: Vec3,
}

/// The primitives' boxes in a uniform grid of cells on the CPU ([`slot_of`]'s buckets,
/// by a counting sort): `entries[starts[b]..starts[b + 1]]` are bucket `b`'s, in the
/// primitives' order.
pub struct BoxGrid {
    shape: Shape,
    starts: Vec<u32>,
    entries: Vec<Entry>,
}

impl Listing for BoxGrid {
    #[inline]
    fn range(&self, b: usize) -> std::ops::Range<usize> {
        self.starts[b] as usize..self.starts[b + 1] as usize
    }

    #[inline]
    fn entry(&self, e: usize) -> (u32, [Vec3; 2]) {
        let e = &self.entries[e];
        (e.id, [e.lo, e.hi])
    }

    #[inline]
    fn cell(&self, e: usize, _: f32) -> Cell {
        self.entries[e].cell
    }
}

impl BoxGrid {
    /// A grid of cells `cell` wide over the boxes of `count` primitives, `corners(k)`
    /// giving primitive k's points. A primitive with a point that is not finite is left
    /// out: no query meets it.
    pub fn new<I: Iterator<Item = Vec3>>(cell: f32, count: usize, corners: impl Fn(usize) -> I) -> Self {
        let size = (4 * count.max(16)).next_power_of_two() as u32;
        let mut extent = Vec3::ZERO;
        let listed: Vec<(u32, Entry)> = (0..count)
            .filter_map(|k| {
                let b = bounds(corners(k));
                let slot = slot_of(b, cell, size)?;
                if slot < size {
                    extent = extent.max(b[1] - b[0]);
                }
                Some((slot, Entry { id: k as u32, cell: cell_of(b[0], 1.0 / cell), lo: b[0], hi: b[1] }))
            })
            .collect();
        let mut starts = vec![0u32; size as usize + 2];
        for (slot, _) in &listed {
            starts[*slot as usize + 1] += 1;
        }
        for b in 1..starts.len() {
            starts[b] += starts[b - 1];
        }
        let mut fill = starts.clone();
        let mut entries = vec![Entry { id: 0, cell: [0; 3], lo: Vec3::ZERO, hi: Vec3::ZERO }; listed.len()];
        for (slot, e) in listed {
            let at = &mut fill[slot as usize];
            entries[*at as usize] = e;
            *at += 1;
        }
        let most_cells = QUERY_CELLS;
        BoxGrid { shape: Shape { cell, size, extent, most_cells }, starts, entries }
    }

    /// Calls `f` once for every primitive numbered `first` or more whose box meets the box
    /// `b` grown by `grow` ([`query`]).
    pub fn query(&self, b: [Vec3; 2], grow: f32, first: u32, f: impl FnMut(u32)) {
        query(self, &self.shape, b, grow, first, f);
    }
}

/// Whether box `e` grown by `grow` meets box `b` (closed: boxes that touch meet) — the
/// one test of [`query`], which the kept pairs' filter
/// (`crate::tri_contact::Contact::begin`) repeats so that it keeps what a search finds.
#[inline]
pub fn boxes_meet(e: [Vec3; 2], b: [Vec3; 2], grow: f32) -> bool {
    let g = Vec3::splat(grow);
    (e[0] - g).cmple(b[1]).all() && b[0].cmple(e[1] + g).all()
}

/// The box of points `xs`, lowest and highest corner.
pub fn bounds(xs: impl Iterator<Item = Vec3>) -> [Vec3; 2] {
    xs.fold([Vec3::INFINITY, Vec3::NEG_INFINITY], |[lo, hi], x| [lo.min(x), hi.max(x)])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_query_meets_every_box_a_brute_force_meets_once_big_boxes_too() {
        // 400 boxes at random in a 1 m cube, most a few cells wide, every 25th wider than
        // BIG_CELLS cells (listed apart), one with a NaN corner (met by nothing); queries
        // of random boxes grown by 0.02, every 20th 1 m wide (more cells than the walk
        // takes: a scan): each call must be a box the exact test meets, each such box
        // called exactly once, from `first` on.
        let mut seed = 7u64;
        let mut r = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 40) as f32 / (1u64 << 24) as f32
        };
        let boxes: Vec<[Vec3; 2]> = (0..400)
            .map(|k| {
                let lo = Vec3::new(r(), r(), r());
                let size = if k % 25 == 0 { 0.5 } else { 0.08 };
                let hi = lo + Vec3::new(r(), r(), r()) * size;
                if k == 7 { [lo, Vec3::new(f32::NAN, 0.0, 0.0)] } else { [lo, hi] }
            })
            .collect();
        let grid = BoxGrid::new(0.05, boxes.len(), |k| boxes[k].into_iter());
        let big = grid.range(grid.shape.size as usize).len();
        assert!(big >= 10, "only {big} wide boxes listed apart: the test would not reach them");
        let grow = 0.02;
        let (mut met, mut scans) = (0, 0);
        for q in 0..200 {
            let lo = Vec3::new(r(), r(), r());
            let b = [lo, lo + Vec3::splat(if q % 20 == 0 { 1.0 } else { 0.03 })];
            let [c0, c1] = query_cells(b, grow, &grid.shape);
            scans += u32::from((c1[0] - c0[0] + 1) * (c1[1] - c0[1] + 1) * (c1[2] - c0[2] + 1) > 4096);
            let first = q as u32;
            let mut calls = vec![0u32; boxes.len()];
            grid.query(b, grow, first, |id| calls[id as usize] += 1);
            for (k, &bk) in boxes.iter().enumerate() {
                let finite = bk[0].is_finite() && bk[1].is_finite();
                let want = u32::from(finite && boxes_meet(bk, b, grow) && k as u32 >= first);
                assert_eq!(calls[k], want, "query {q}, box {k}");
                met += want;
            }
        }
        // Measured 1 000-odd meetings and 10 scans: enough that a missed or doubled box
        // shows, in both ways of walking.
        assert!(met > 500, "only {met} boxes met in all: the test would hold little");
        assert!(scans >= 5, "only {scans} queries scanned: the wide queries' path went untested");
    }

    #[test]
    fn a_row_of_cells_is_a_run_of_buckets_and_near_rows_never_share_one() {
        // The rule every grid relies on: x + 1 is the next bucket; rows within two cells
        // of each other in y and z start at least four buckets apart in a table of 64.
        for (y, z) in [(0, 0), (-3, 7), (1000, -1000)] {
            for x in -5..5 {
                assert_eq!(bucket([x + 1, y, z], 1 << 16), (bucket([x, y, z], 1 << 16) + 1) & 0xffff);
            }
            for dy in -2..=2 {
                for dz in -2..=2 {
                    if (dy, dz) != (0, 0) {
                        let apart = row_start(y + dy, z + dz).wrapping_sub(row_start(y, z)) & 63;
                        assert!((4..=60).contains(&apart), "rows ({y}, {z}) and +({dy}, {dz}): {apart} apart");
                    }
                }
            }
        }
    }
}
