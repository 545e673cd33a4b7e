//! The per-particle tables every solver reads, and the grid's sizes of them: a module of
//! its own, without dependencies, so that the grid builder and the mesh reader share them
//! without depending on each other.

/// Spring slots per particle in the grid's gather table (a mesh's rows have any length).
pub const SLOTS: usize = 12;
/// Slots `0 .. STRAIN_SLOTS` of a grid's row (its structural and shear springs) are held
/// by the strain limit (a mesh's: the edges at the head of its row).
pub const STRAIN_SLOTS: usize = 8;
/// Face slots per particle of a grid: a regular grid vertex touches at most six triangles.
pub const FACE_SLOTS: usize = 6;
/// Tether slots per particle (long-range attachments to pins).
pub const TETHER_SLOTS: usize = 2;
/// Fixed-point units of a contact's push per thickness (the particle contact's and the
/// triangles'; a push is at most the thickness: 2¹⁶ units): integers add up to the same
/// bits in any order.
pub const CONTACT_UNITS: f32 = 65536.0;
/// The most particles a mesh may have for self-collision: a hash slot's word holds the
/// particle's index in 24 bits (`cpu::self_collide::slot_word`).
pub const SELF_COLLISION_MAX_PARTICLES: usize = 1 << 24;

/// Per-particle lists (spring slots, faces around a vertex): rows of one fixed width (the
/// grid's table, where empty entries pad a row) or ranges into one flat list (a mesh's
/// compressed rows, CSR: row `i` is `start[i] .. start[i + 1]`, of any length). A row's
/// head (`head(i)`) is its strain-limited part: the first [`STRAIN_SLOTS`] of a fixed
/// row, the edges of a mesh vertex (which its row lists before its bending springs).
/// The GPU kernels read a mesh's rows through one buffer of `(start, head end, face start,
/// 0)` per particle and one past the last (`clothlab_engine::tables::adjacency`).
#[derive(Debug, Clone, PartialEq)]
pub struct Rows<T> {
    entries: Vec<T>,
    bounds: Bounds,
}

#[derive(Debug, Clone, PartialEq)]
enum Bounds {
    /// Rows of `width` entries, the first `head` of them the head.
    Fixed { width: usize, head: usize },
    /// Row `i` is `start[i] .. start[i + 1]`, its head `start[i] .. head_end[i]`.
    Csr { start: Vec<u32>, head_end: Vec<u32> },
}

impl<T: Copy> Rows<T> {
    /// Rows of `width` entries each (`entries.len()` a multiple of it), the first `head`
    /// of each the head.
    pub fn fixed(entries: Vec<T>, width: usize, head: usize) -> Self {
        assert!(width > 0 && head <= width && entries.len().is_multiple_of(width), "fixed rows of {width}");
        Self { entries, bounds: Bounds::Fixed { width, head } }
    }

    /// Compressed rows: row `i` is `lists[i]`, its head the first `heads[i]` entries (all
    /// of the row where `heads` is `None`).
    pub fn compressed(lists: &[Vec<T>], heads: Option<&[usize]>) -> Self {
        let total: usize = lists.iter().map(Vec::len).sum();
        let mut entries = Vec::with_capacity(total);
        let mut start = Vec::with_capacity(lists.len() + 1);
        let mut head_end = Vec::with_capacity(lists.len());
        for (i, list) in lists.iter().enumerate() {
            let s = entries.len();
            start.push(s as u32);
            let h = heads.map_or(list.len(), |h| h[i].min(list.len()));
            head_end.push((s + h) as u32);
            entries.extend_from_slice(list);
        }
        start.push(entries.len() as u32);
        Self { entries, bounds: Bounds::Csr { start, head_end } }
    }

    /// How many rows.
    pub fn rows(&self) -> usize {
        match &self.bounds {
            Bounds::Fixed { width, .. } => self.entries.len() / width,
            Bounds::Csr { head_end, .. } => head_end.len(),
        }
    }

    /// The range of row `i` in [`Self::entries`].
    #[inline(always)]
    pub fn range(&self, i: usize) -> std::ops::Range<usize> {
        match &self.bounds {
            Bounds::Fixed { width, .. } => i * width..(i + 1) * width,
            Bounds::Csr { start, .. } => start[i] as usize..start[i + 1] as usize,
        }
    }

    /// Row `i`.
    #[inline(always)]
    pub fn row(&self, i: usize) -> &[T] {
        &self.entries[self.range(i)]
    }

    /// Row `i`'s head (its strain-limited entries).
    #[inline(always)]
    pub fn head(&self, i: usize) -> &[T] {
        match &self.bounds {
            Bounds::Fixed { width, head } => &self.entries[i * width..i * width + head],
            Bounds::Csr { start, head_end } => &self.entries[start[i] as usize..head_end[i] as usize],
        }
    }

    /// Row `i`, to change in place.
    pub fn row_mut(&mut self, i: usize) -> &mut [T] {
        let r = self.range(i);
        &mut self.entries[r]
    }

    /// Every row's entries, row after row.
    pub fn entries(&self) -> &[T] {
        &self.entries
    }

    /// Every row's entries, to change in place (the rows stay as they are).
    pub fn entries_mut(&mut self) -> &mut [T] {
        &mut self.entries
    }

    /// The fixed width, or `None` for compressed rows.
    pub fn width(&self) -> Option<usize> {
        match self.bounds {
            Bounds::Fixed { width, .. } => Some(width),
            Bounds::Csr { .. } => None,
        }
    }

    /// Compressed rows' `(start, head end)` of row `i`, for `i` up to [`Self::rows`]
    /// (the last row's end); `None` for fixed rows.
    pub fn csr_bounds(&self, i: usize) -> Option<(u32, u32)> {
        match &self.bounds {
            Bounds::Fixed { .. } => None,
            Bounds::Csr { start, head_end } => Some((start[i], head_end.get(i).copied().unwrap_or(start[i]))),
        }
    }

    /// The longest row's length.
    pub fn max_row(&self) -> usize {
        (0..self.rows()).map(|i| self.range(i).len()).max().unwrap_or(0)
    }
}

/// A colouring of the particles (Vertex Block Descent's, `cpu::vbd::colouring`): the
/// particles listed colour by colour, colour `k` being `order[bounds[k] .. bounds[k + 1]]`,
/// no two particles of one colour joined by a spring. The GPU reads `order` as
/// `clothlab_core::layout::Buf::Colours` and sweeps a colour as one dispatch over its
/// range.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Colours {
    /// Every particle once, colour by colour.
    pub order: Vec<u32>,
    /// Where each colour starts in `order`, and one past the last colour's end.
    pub bounds: Vec<u32>,
    /// Each particle's colour (the contact between triangles' terms under VBD are
    /// gathered for one colour at a time).
    pub of: Vec<u32>,
}

impl Colours {
    /// The colouring whose colour `k` is `lists[k]`.
    pub fn from_lists(lists: &[Vec<u32>]) -> Self {
        let mut bounds = vec![0u32];
        let mut order = Vec::with_capacity(lists.iter().map(Vec::len).sum());
        for l in lists {
            order.extend_from_slice(l);
            bounds.push(order.len() as u32);
        }
        let mut of = vec![0u32; order.len()];
        for (c, l) in lists.iter().enumerate() {
            for &k in l {
                if let Some(slot) = of.get_mut(k as usize) {
                    *slot = c as u32;
                }
            }
        }
        Self { order, bounds, of }
    }

    /// The GPU's words ([`crate::layout::Buf::Colours`]): `order`, then `of`.
    pub fn words(&self) -> Vec<u32> {
        let mut v = self.order.clone();
        v.extend_from_slice(&self.of);
        v
    }

    /// How many colours.
    pub fn len(&self) -> usize {
        self.bounds.len().saturating_sub(1)
    }

    /// Whether there is no colour (no particle).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The colours, each as `(first, count)` in `order`.
    pub fn ranges(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        self.bounds.windows(2).map(|w| (w[0], w[1] - w[0]))
    }

    /// The particles of colour `k`.
    pub fn colour(&self, k: usize) -> &[u32] {
        &self.order[self.bounds[k] as usize..self.bounds[k + 1] as usize]
    }

    /// The colours as lists.
    pub fn lists(&self) -> Vec<Vec<u32>> {
        (0..self.len()).map(|k| self.colour(k).to_vec()).collect()
    }

    /// The colouring of an n × n grid whose springs reach 2 particles along a row or a
    /// column (the 12-slot stencil): the 9 classes `(i mod 3, j mod 3)`, two particles of
    /// one class being 3 apart or more. Each class in particle order.
    pub fn grid(n: usize) -> Vec<Vec<u32>> {
        let mut lists = vec![Vec::new(); 9];
        for k in 0..n * n {
            lists[(k % n) % 3 + 3 * ((k / n) % 3)].push(k as u32);
        }
        lists.retain(|c| !c.is_empty());
        lists
    }

    /// A greedy colouring of `count` particles, particle `i`'s neighbours (the other ends
    /// of its springs) `neighbours(i)`: in particle order, each the smallest colour none of
    /// its neighbours has yet.
    pub fn greedy<I: IntoIterator<Item = usize>>(count: usize, neighbours: impl Fn(usize) -> I) -> Vec<Vec<u32>> {
        let mut colour_of = vec![u32::MAX; count];
        let mut used = Vec::new();
        for i in 0..count {
            used.clear();
            used.extend(neighbours(i).into_iter().map(|j| colour_of[j]));
            colour_of[i] = (0..).find(|c| !used.contains(c)).unwrap_or(0);
        }
        let colours = colour_of.iter().copied().max().map_or(0, |c| c as usize + 1);
        let mut lists = vec![Vec::new(); colours];
        for (k, &c) in colour_of.iter().enumerate() {
            lists[c as usize].push(k as u32);
        }
        lists
    }
}

/// The edges of `triangles`, each once (lower index first), sorted.
pub fn edges(triangles: &[[u32; 3]]) -> Vec<[u32; 2]> {
    let mut e: Vec<[u32; 2]> = triangles
        .iter()
        .flat_map(|t| [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]])
        .map(|[a, b]| [a.min(b), a.max(b)])
        .collect();
    e.sort_unstable();
    e.dedup();
    e
}
