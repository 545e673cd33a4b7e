//! A uniform grid of cells over primitives' boxes, by a counting sort into hashed buckets:
//! the broad phase of the contact between triangles (`crate::tri_contact::find_pairs`) and
//! of the crossings' count (`crate::crossings::count`), written once.

use glam::Vec3;

/// A cell's integer coordinates.
pub(crate) type Cell = [i32; 3];

/// The primitives' boxes in a uniform grid of cells, by a counting sort into hashed
/// buckets: `entries[starts[b]..starts[b + 1]]` are the primitives whose box covers a cell
/// that hashes to bucket `b` (cells of other boxes may share it: a query checks the cell).
pub(crate) struct BoxGrid {
    inv_cell: f32,
    mask: usize,
    starts: Vec<u32>,
    entries: Vec<u32>,
    /// Each primitive's box in cells, lowest and highest (a primitive with a coordinate
    /// that is not finite has an empty box: lowest above highest).
    boxes: Vec<[Cell; 2]>,
    /// Each primitive's box, lowest and highest corner (the exact test's first filter).
    corners: Vec<[Vec3; 2]>,
}

/// Cell coordinates are clamped to this before they become integers (a far particle
/// shares the border cells instead of overflowing).
const CELL_LIMIT: f32 = 1e6;

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

    /// The box of points `xs` grown by `grow`, in cells (empty if a point is not finite).
    pub(crate) fn cells_of(&self, b: [Vec3; 2], grow: f32) -> [Cell; 2] {
        let [lo, hi] = b;
        if !(lo.is_finite() && hi.is_finite()) {
            return [[1; 3], [0; 3]];
        }
        [self.cell(lo - Vec3::splat(grow)), self.cell(hi + Vec3::splat(grow))]
    }

    /// Whether primitive `id`'s box meets box `b` grown by `grow`.
    pub(crate) fn meets(&self, id: u32, b: [Vec3; 2], grow: f32) -> bool {
        let [lo, hi] = self.corners[id as usize];
        (lo - Vec3::splat(grow)).cmple(b[1]).all() && b[0].cmple(hi + Vec3::splat(grow)).all()
    }

    /// A grid of cells `cell` wide over the boxes of `count` primitives, `corners(k)`
    /// giving primitive k's points.
    pub(crate) fn new<I: Iterator<Item = Vec3>>(cell: f32, count: usize, corners: impl Fn(usize) -> I) -> Self {
        let size = (4 * count.max(1)).next_power_of_two();
        let mut g = BoxGrid {
            inv_cell: 1.0 / cell,
            mask: size - 1,
            starts: vec![0; size + 1],
            entries: Vec::new(),
            boxes: Vec::with_capacity(count),
            corners: Vec::with_capacity(count),
        };
        for k in 0..count {
            let b = bounds(corners(k));
            g.boxes.push(g.cells_of(b, 0.0));
            g.corners.push(b);
        }
        let each = |b: &[Cell; 2], f: &mut dyn FnMut(Cell)| {
            for i in b[0][0]..=b[1][0] {
                for j in b[0][1]..=b[1][1] {
                    for k in b[0][2]..=b[1][2] {
                        f([i, j, k]);
                    }
                }
            }
        };
        let mut counts = vec![0u32; size];
        for b in &g.boxes {
            each(b, &mut |c| counts[g.bucket(c)] += 1);
        }
        let mut total = 0;
        for (b, n) in counts.iter().enumerate() {
            total += n;
            g.starts[b + 1] = total;
        }
        let mut entries = vec![0; total as usize];
        let mut fill: Vec<u32> = g.starts[..size].to_vec();
        for (id, b) in g.boxes.iter().enumerate() {
            each(b, &mut |c| {
                let slot = &mut fill[g.bucket(c)];
                entries[*slot as usize] = id as u32;
                *slot += 1;
            });
        }
        g.entries = entries;
        g
    }

    /// Calls `f` once for every primitive whose box meets the box `q` (in cells): in the
    /// lowest cell the two boxes share, so that a primitive covering several is met once.
    pub(crate) fn query(&self, q: [Cell; 2], mut f: impl FnMut(u32)) {
        for i in q[0][0]..=q[1][0] {
            for j in q[0][1]..=q[1][1] {
                for k in q[0][2]..=q[1][2] {
                    let c = [i, j, k];
                    let b = self.bucket(c);
                    for &id in &self.entries[self.starts[b] as usize..self.starts[b + 1] as usize] {
                        let [lo, hi] = self.boxes[id as usize];
                        let inside = (0..3).all(|a| lo[a] <= c[a] && c[a] <= hi[a]);
                        let lowest = (0..3).all(|a| c[a] == lo[a].max(q[0][a]));
                        if inside && lowest {
                            f(id);
                        }
                    }
                }
            }
        }
    }
}

/// The box of points `xs`, lowest and highest corner.
pub(crate) fn bounds(xs: impl Iterator<Item = Vec3>) -> [Vec3; 2] {
    xs.fold([Vec3::INFINITY, Vec3::NEG_INFINITY], |[lo, hi], x| [lo.min(x), hi.max(x)])
}
