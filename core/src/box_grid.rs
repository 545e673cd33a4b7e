//! A uniform grid of cells over primitives' boxes, by a counting sort into hashed buckets:
//! the broad phase of the contact between triangles (`crate::tri_contact::find_pairs`) and
//! of the crossings' count (`crate::crossings::count`), written once.
//!
//! Each primitive is listed once, in the cell of its box's lowest corner; a query looks
//! in the cells from its own box's lowest corner less the largest box's extent to its
//! highest corner, so it meets every box that can reach it, each once — no primitive is
//! listed in every cell it covers, and no query has to tell copies apart. (Listing each box
//! in every cell it covers, each pair met in the lowest cell the two shared, visited
//! 2–3 times the entries in a pile of sheets and took three quarters of the contact's time.)

use glam::Vec3;

/// A cell's integer coordinates.
pub(crate) type Cell = [i32; 3];

/// A primitive in its bucket: the cell of its box's lowest corner (a bucket holds the
/// primitives of every cell that hashes to it), its index and its box.
#[derive(Debug, Clone, Copy)]
struct Entry {
    cell: Cell,
    id: u32,
    lo: Vec3,
    hi: Vec3,
}

/// The primitives' boxes in a uniform grid of cells, by a counting sort into hashed
/// buckets: `entries[starts[b]..starts[b + 1]]` are the primitives whose box's lowest
/// corner lies in a cell that hashes to bucket `b`.
pub(crate) struct BoxGrid {
    inv_cell: f32,
    cell: f32,
    mask: usize,
    starts: Vec<u32>,
    entries: Vec<Entry>,
    /// The largest extent of a listed box on each axis.
    extent: Vec3,
    /// Boxes wider than [`BIG_CELLS`] cells on some axis: tested by every query instead
    /// of widening every query to them.
    big: Vec<Entry>,
}

/// Cell coordinates are clamped to this before they become integers (a far particle
/// shares the border cells instead of overflowing).
const CELL_LIMIT: f32 = 1e6;

/// A box wider than this many cells on some axis is kept apart ([`BoxGrid::big`]).
const BIG_CELLS: f32 = 4.0;

impl BoxGrid {
    fn cell(&self, x: Vec3) -> Cell {
        let c = (x * self.inv_cell).floor().clamp(Vec3::splat(-CELL_LIMIT), Vec3::splat(CELL_LIMIT));
        [c.x as i32, c.y as i32, c.z as i32]
    }

    fn bucket(&self, c: Cell) -> usize {
        let h = (c[0] as u32).wrapping_mul(73_856_093)
            ^ (c[1] as u32).wrapping_mul(19_349_663)
            ^ (c[2] as u32).wrapping_mul(83_492_791);
        h as usize & self.mask
    }

    /// A grid of cells `cell` wide over the boxes of `count` primitives, `corners(k)`
    /// giving primitive k's points. A primitive with a point that is not finite is left
    /// out: no query meets it.
    pub(crate) fn new<I: Iterator<Item = Vec3>>(cell: f32, count: usize, corners: impl Fn(usize) -> I) -> Self {
        let size = (4 * count.max(1)).next_power_of_two();
        let mut g = BoxGrid {
            inv_cell: 1.0 / cell,
            cell,
            mask: size - 1,
            starts: vec![0; size + 1],
            entries: Vec::new(),
            extent: Vec3::ZERO,
            big: Vec::new(),
        };
        let mut listed = Vec::with_capacity(count);
        for k in 0..count {
            let [lo, hi] = bounds(corners(k));
            if !(lo.is_finite() && hi.is_finite()) {
                continue;
            }
            let e = Entry { cell: g.cell(lo), id: k as u32, lo, hi };
            if (hi - lo).max_element() > BIG_CELLS * cell {
                g.big.push(e);
            } else {
                g.extent = g.extent.max(hi - lo);
                listed.push(e);
            }
        }
        let mut counts = vec![0u32; size];
        for e in &listed {
            counts[g.bucket(e.cell)] += 1;
        }
        let mut total = 0;
        for (b, n) in counts.iter().enumerate() {
            total += n;
            g.starts[b + 1] = total;
        }
        let mut fill: Vec<u32> = g.starts[..size].to_vec();
        let mut entries = vec![Entry { cell: [0; 3], id: 0, lo: Vec3::ZERO, hi: Vec3::ZERO }; listed.len()];
        for e in listed {
            let slot = &mut fill[g.bucket(e.cell)];
            entries[*slot as usize] = e;
            *slot += 1;
        }
        g.entries = entries;
        g
    }

    /// Calls `f` once for every primitive numbered `first` or more whose box meets the box
    /// `b` grown by `grow` (closed: boxes that touch meet). A search of pairs among the
    /// primitives of one grid passes the one after its own, so that each pair is met once
    /// and the others cost an integer test.
    pub(crate) fn query(&self, b: [Vec3; 2], grow: f32, first: u32, mut f: impl FnMut(u32)) {
        let [lo, hi] = b;
        if !(lo.is_finite() && hi.is_finite()) {
            return;
        }
        let meets = |e: &Entry| boxes_meet([e.lo, e.hi], b, grow);
        // A little more than rounding can move a corner (the test above decides).
        let g = Vec3::splat(grow);
        let slack = Vec3::splat(1e-4 * self.cell + 1e-6 * lo.abs().max(hi.abs()).max_element());
        let [c0, c1] = [self.cell(lo - g - self.extent - slack), self.cell(hi + g + slack)];
        for i in c0[0]..=c1[0] {
            for j in c0[1]..=c1[1] {
                for k in c0[2]..=c1[2] {
                    let c = [i, j, k];
                    let bucket = self.bucket(c);
                    for e in &self.entries[self.starts[bucket] as usize..self.starts[bucket + 1] as usize] {
                        if e.id >= first && e.cell == c && meets(e) {
                            f(e.id);
                        }
                    }
                }
            }
        }
        for e in &self.big {
            if e.id >= first && meets(e) {
                f(e.id);
            }
        }
    }
}

/// Whether box `e` grown by `grow` meets box `b` (closed: boxes that touch meet) — the
/// one test of [`BoxGrid::query`], which the kept pairs' filter
/// (`crate::tri_contact::Contact::begin`) repeats so that it keeps what a search finds.
pub(crate) fn boxes_meet(e: [Vec3; 2], b: [Vec3; 2], grow: f32) -> bool {
    let g = Vec3::splat(grow);
    (e[0] - g).cmple(b[1]).all() && b[0].cmple(e[1] + g).all()
}

/// The box of points `xs`, lowest and highest corner.
pub(crate) fn bounds(xs: impl Iterator<Item = Vec3>) -> [Vec3; 2] {
    xs.fold([Vec3::INFINITY, Vec3::NEG_INFINITY], |[lo, hi], x| [lo.min(x), hi.max(x)])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_query_meets_every_box_a_brute_force_meets_once_big_boxes_too() {
        // 400 boxes at random in a 1 m cube, most a few cells wide, every 25th wider than
        // BIG_CELLS cells (kept apart), one with a NaN corner (met by nothing); queries of
        // random boxes grown by 0.02: each call must be a box the exact test meets, each
        // such box called exactly once, from `first` on.
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
        assert!(!grid.big.is_empty(), "the test would not reach the wide boxes");
        let grow = 0.02;
        let mut met = 0;
        for q in 0..200 {
            let lo = Vec3::new(r(), r(), r());
            let b = [lo, lo + Vec3::splat(0.03)];
            let first = q as u32;
            let mut calls = vec![0u32; boxes.len()];
            grid.query(b, grow, first, |id| calls[id as usize] += 1);
            for (k, [blo, bhi]) in boxes.iter().enumerate() {
                let finite = blo.is_finite() && bhi.is_finite();
                let meets = finite
                    && (*blo - Vec3::splat(grow)).cmple(b[1]).all()
                    && b[0].cmple(*bhi + Vec3::splat(grow)).all();
                let want = u32::from(meets && k as u32 >= first);
                assert_eq!(calls[k], want, "query {q}, box {k}");
                met += want;
            }
        }
        // Measured 135 meetings: enough that a missed or doubled box shows.
        assert!(met > 100, "only {met} boxes met in all: the test would hold little");
    }
}
