//! The contact between triangles as GPU kernels see it (`shaders/wgsl/tri_*.wgsl`): one
//! function per kernel, each the kernel's CPU twin, on the buffers the kernels share —
//! the edges ([`TriLayout::edges_words`]: a header, then two vertices an edge), a
//! particle's start and bound (`[x, y, z, bound]`), the integers ([`TriLayout`]: the
//! scalars, the two grids' buckets and entries, each owner's count of pairs, each
//! particle's fixed-point sums) and the pairs ([`TRI_SLOTS`] an owner).
//!
//! They are what the GPU solvers' kernels are checked against and what the CPU solvers
//! run (`crate::tri_pipeline::Contact`: these functions in the recipe's order, the pairs
//! from the pairs it keeps between searches instead of the grid's walk, through
//! [`keep_pairs`]): the pairs do not depend on the broad phase (an owner keeps its
//! [`TRI_SLOTS`] nearest; the scalars count what did not fit), and every sum is an
//! integer sum, so both give the same bits.
//!
//! Owners: vertex `v` (`0 ≤ o < np`) owns its vertex–triangle pairs, edge `e` (`o = np +
//! e`) its edge–edge pairs with the edges numbered above it.

use glam::Vec3;
use rayon::prelude::*;

use clothlab_core::grid::V4;
use clothlab_core::step_params::StepParams;
use clothlab_core::tri_contact::{BOUND_FRACTION, MAX_REACH_SPACINGS, Pair, REACH_PER_MOTION, ee_pair, vt_pair};

pub use clothlab_core::layout::TRI_SLOTS;

pub use clothlab_core::layout::tri_at as at;

/// The fixed-point units of the velocity pass's and the separation's sums.
const UNITS: f32 = clothlab_core::tables::CONTACT_UNITS;

/// Where the contact's integers lie, in u32 words, for a cloth of `np` particles, `tris`
/// triangles and `edges` edges.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TriLayout {
    /// Particles.
    pub np: usize,
    /// Triangles.
    pub tris: usize,
    /// Edges.
    pub edges: usize,
    /// Buckets of each grid (a power of two, at least twice the primitives of either).
    pub buckets: usize,
}

impl TriLayout {
    /// The layout of a cloth of these sizes.
    pub fn new(np: usize, tris: usize, edges: usize) -> Self {
        Self { np, tris, edges, buckets: (2 * tris.max(edges).max(1)).next_power_of_two() }
    }

    /// The layout of `topo`'s cloth.
    pub fn of(topo: &clothlab_core::grid::ClothTopology) -> Self {
        Self::new(topo.num_particles(), topo.triangles.len(), topo.edges().len())
    }

    /// The grids' bucket counts (the triangles' buckets and their wide boxes' bucket,
    /// then the edges'), then after the scan and the scatter each bucket's end.
    pub fn grid(&self) -> usize {
        self.vbd() + clothlab_core::tri_contact::VBD_TERMS * self.np
    }

    /// The buckets of one grid: its cells' [`TriLayout::buckets`] and the wide boxes' one
    /// after them ([`clothlab_core::broad::slot_of`]).
    pub fn grid_buckets(&self) -> usize {
        self.buckets + 1
    }

    /// The grids' entries: the triangles' (by bucket), then the edges'.
    pub fn entries(&self) -> usize {
        self.grid() + 2 * self.grid_buckets()
    }

    /// Each owner's count of pairs found (may exceed [`TRI_SLOTS`]).
    pub fn owners(&self) -> usize {
        self.entries() + self.tris + self.edges
    }

    /// Each particle's fixed-point sums: x, y, z, then its count of acting pairs (i32).
    pub fn sums(&self) -> usize {
        self.owners() + self.np + self.edges
    }

    /// VBD's contact terms, after the scalars: [`clothlab_core::tri_contact::VBD_TERMS`] words a
    /// particle (i32; where a kernel finds them without the edges' header).
    pub fn vbd(&self) -> usize {
        at::WORDS
    }

    /// Words of the integers.
    pub fn words(&self) -> usize {
        self.sums() + 4 * self.np
    }

    /// Words of the pairs: [`TRI_SLOTS`] an owner (the other primitive), then as many
    /// again (each kept pair's distance, f32 bits: which one a nearer pair replaces).
    pub fn pair_words(&self) -> usize {
        2 * self.num_owners() * TRI_SLOTS as usize
    }

    /// Owners: the vertices, then the edges.
    pub fn num_owners(&self) -> usize {
        self.np + self.edges
    }

    /// The edges' buffer: `[triangles, edges, buckets, 0]`, then each edge's two vertices
    /// (the header's 0 is a zero the shader compilers cannot see: the kernels pass a
    /// side's weights through it so that no compiler rewrites (1 − s)·a + s·b as a lerp).
    pub fn edges_words(&self, edges: &[[u32; 2]]) -> Vec<u32> {
        let mut v = vec![self.tris as u32, self.edges as u32, self.buckets as u32, 0];
        v.extend(edges.iter().flatten());
        v
    }
}

/// The buffers of the contact's kernels, as their twins see them.
pub struct TriBufs<'a> {
    /// The layout.
    pub l: TriLayout,
    /// Each particle's start position and bound (f32 bits in w).
    pub floats: &'a mut [V4],
    /// The integers.
    pub ints: &'a mut [u32],
    /// The pairs.
    pub pairs: &'a mut [u32],
    /// The owners (or particles) a task takes on rayon's threads: 1 for `cpu-par`,
    /// `usize::MAX` for one task (`cpu`, and the twins of a kernel test).
    pub min_len: usize,
}

/// The primitives the contact pairs: the cloths' triangles and their edges
/// (`clothlab_core::tables::edges`, as `ClothTopology::edges`).
#[derive(Debug, Clone, Copy)]
pub struct Prims<'a> {
    /// The triangles.
    pub triangles: &'a [[u32; 3]],
    /// The edges.
    pub edges: &'a [[u32; 2]],
}

impl<'a> Prims<'a> {
    /// `topo`'s triangles and edges.
    pub fn of(topo: &'a clothlab_core::grid::ClothTopology) -> Self {
        Self { triangles: &topo.triangles, edges: topo.edges() }
    }
}

fn v3(x: &V4) -> Vec3 {
    Vec3::new(x[0], x[1], x[2])
}

fn f(bits: u32) -> f32 {
    f32::from_bits(bits)
}

/// `tri_speed`: the fastest free vertex's speed into the scalars (the integers cleared
/// before).
pub fn tri_speed(pos: &[V4], vel: &[V4], b: &mut TriBufs) {
    for (x, v) in pos.iter().zip(vel) {
        let s = v3(v).length();
        if x[3] > 0.0 && s.is_finite() {
            b.ints[at::SPEED] = b.ints[at::SPEED].max(s.to_bits());
        }
    }
}

/// The substep's reach from the fastest free vertex's speed: how far the bounds look at
/// the substep's start — the thickness, or farther where the cloth moves fast, far enough
/// that a vertex with nothing near may move 1.25 times the fastest vertex's motion
/// (`|v| dt + |g| dt²`), at most the thickness plus [`MAX_REACH_SPACINGS`] rest spacings
/// (a constant, so that no sum over the edges is taken a substep).
pub fn reach_of(p: &StepParams, fastest: f32) -> f32 {
    let g = Vec3::new(p.gravity[0], p.gravity[1], p.gravity[2]).length();
    let motion = fastest * p.dt + g * (p.dt * p.dt);
    let t = p.self_thickness;
    (REACH_PER_MOTION * motion).clamp(t, t + MAX_REACH_SPACINGS * p.spacing)
}

/// `tri_start`: each particle's start position and its bound at the reach's fraction;
/// the reach and the grids' cell into the scalars.
pub fn tri_start(p: &StepParams, pos: &[V4], b: &mut TriBufs) {
    let reach = reach_of(p, f(b.ints[at::SPEED]));
    for (s, x) in b.floats.iter_mut().zip(pos) {
        *s = [x[0], x[1], x[2], BOUND_FRACTION * reach];
    }
    b.ints[at::REACH] = reach.to_bits();
    b.ints[at::CELL] = (2.0 * reach).max(1.5 * p.spacing).to_bits();
}

/// The box of primitive `o` (triangles first, then edges).
fn prim_box(o: usize, pos: &[V4], tris: &[[u32; 3]], edges: &[[u32; 2]]) -> [Vec3; 2] {
    let at = |k: u32| v3(&pos[k as usize]);
    if o < tris.len() {
        let [a, b, c] = tris[o];
        let (a, b, c) = (at(a), at(b), at(c));
        [a.min(b).min(c), a.max(b).max(c)]
    } else {
        let [a, b] = edges[o - tris.len()];
        let (a, b) = (at(a), at(b));
        [a.min(b), a.max(b)]
    }
}

/// Primitive `o`'s bucket among both grids' (the triangles', then the edges', each
/// [`TriLayout::buckets`] and one for the wide boxes: [`clothlab_core::broad::slot_of`]) and its
/// box, or `None` where its box is not finite.
fn bucket_of(o: usize, pos: &[V4], m: Prims, l: &TriLayout, cell: f32) -> Option<(usize, [Vec3; 2])> {
    let bx = prim_box(o, pos, m.triangles, m.edges);
    let slot = clothlab_core::broad::slot_of(bx, cell, l.buckets as u32)?;
    let grid = if o < l.tris { 0 } else { l.grid_buckets() };
    Some((grid + slot as usize, bx))
}

/// `tri_grid_count`: each primitive one more in its bucket's count, its box's extent into
/// its grid's largest (a wide box's not: it is listed apart).
pub fn tri_grid_count(m: Prims, pos: &[V4], b: &mut TriBufs) {
    let cell = f(b.ints[at::CELL]);
    for o in 0..b.l.tris + b.l.edges {
        let Some((bucket, [lo, hi])) = bucket_of(o, pos, m, &b.l, cell) else { continue };
        b.ints[b.l.grid() + bucket] += 1;
        if clothlab_core::broad::is_big([lo, hi], cell) {
            continue;
        }
        let ext = if o < b.l.tris { at::EXTENT_T } else { at::EXTENT_E };
        for c in 0..3 {
            b.ints[ext + c] = b.ints[ext + c].max((hi[c] - lo[c]).to_bits());
        }
    }
}

/// `tri_grid_scan`: the buckets' counts to their exclusive prefix (each bucket's start).
pub fn tri_grid_scan(b: &mut TriBufs) {
    let mut acc = 0u32;
    for w in &mut b.ints[b.l.grid()..b.l.entries()] {
        let n = *w;
        *w = acc;
        acc += n;
    }
}

/// `tri_grid_scatter`: each primitive into its bucket's next entry (its bucket's word
/// becomes the bucket's end).
pub fn tri_grid_scatter(m: Prims, pos: &[V4], b: &mut TriBufs) {
    let cell = f(b.ints[at::CELL]);
    for o in 0..b.l.tris + b.l.edges {
        let Some((bucket, _)) = bucket_of(o, pos, m, &b.l, cell) else { continue };
        let slot = b.ints[b.l.grid() + bucket] as usize;
        b.ints[b.l.grid() + bucket] += 1;
        let id = if o < b.l.tris { o } else { o - b.l.tris };
        b.ints[b.l.entries() + slot] = id as u32;
    }
}

/// Bucket `k`'s entries (of both grids' [`TriLayout::grid_buckets`]), after the scatter.
fn bucket_range(ints: &[u32], l: &TriLayout, k: usize) -> std::ops::Range<usize> {
    let start = if k == 0 { 0 } else { ints[l.grid() + k - 1] as usize };
    l.entries() + start..l.entries() + ints[l.grid() + k] as usize
}

/// `tri_grid_sort`: each bucket's entries in increasing order (the scatter's atomics put
/// them in any order).
pub fn tri_grid_sort(b: &mut TriBufs) {
    for k in 0..2 * b.l.grid_buckets() {
        let r = bucket_range(b.ints, &b.l, k);
        b.ints[r].sort_unstable();
    }
}

/// One grid of the GPU buffers (`grid` 0: triangles, 1: edges) as
/// [`clothlab_core::broad::query`] walks it: the entries after the scatter and the sort, each
/// box from the positions.
struct Listed<'a> {
    ints: &'a [u32],
    l: TriLayout,
    pos: &'a [V4],
    m: Prims<'a>,
    grid: usize,
}

impl clothlab_core::broad::Listing for Listed<'_> {
    fn range(&self, b: usize) -> std::ops::Range<usize> {
        bucket_range(self.ints, &self.l, self.grid * self.l.grid_buckets() + b)
    }

    fn entry(&self, e: usize) -> (u32, [Vec3; 2]) {
        let id = self.ints[e];
        let offset = if self.grid == 0 { 0 } else { self.l.tris };
        (id, prim_box(offset + id as usize, self.pos, self.m.triangles, self.m.edges))
    }
}

/// Calls `f` with every primitive of one grid (`grid` 0: triangles, 1: edges) numbered
/// `first` or more whose box meets `b` grown by `grow`: [`clothlab_core::broad::query`] over the
/// buffers, as the kernel walks them.
#[allow(clippy::too_many_arguments)]
fn query(
    ints: &[u32],
    l: &TriLayout,
    pos: &[V4],
    m: Prims,
    grid: usize,
    b: [Vec3; 2],
    grow: f32,
    first: u32,
    f: impl FnMut(u32),
) {
    let cell = self::f(ints[at::CELL]);
    let ext_at = if grid == 0 { at::EXTENT_T } else { at::EXTENT_E };
    let extent = Vec3::new(self::f(ints[ext_at]), self::f(ints[ext_at + 1]), self::f(ints[ext_at + 2]));
    let shape = clothlab_core::broad::Shape {
        cell,
        size: l.buckets as u32,
        extent,
        most_cells: clothlab_core::layout::TRI_QUERY_CELLS,
    };
    clothlab_core::broad::query(&Listed { ints, l: *l, pos, m, grid }, &shape, b, grow, first, f);
}

/// Lowers vertex `k`'s bound to `bound` (the kernels' atomic minimum on its bits).
fn lower(floats: &mut [V4], k: u32, bound: f32) {
    let w = &mut floats[k as usize][3];
    if bound.to_bits() < w.to_bits() {
        *w = bound;
    }
}

/// Whether a pair `(distance, other)` lies after another in the order of nearness
/// (distance, then index: no two of an owner's pairs tie).
fn farther(a: (f32, u32), b: (f32, u32)) -> bool {
    a.0 > b.0 || (a.0 == b.0 && a.1 > b.1)
}

/// `tri_pairs`: each owner's pairs closer than the reach, found by walking the grid
/// ([`keep_pairs`] keeps them).
pub fn tri_pairs(m: Prims, pos: &[V4], b: &mut TriBufs) {
    let l = b.l;
    let reach = f(b.ints[at::REACH]);
    let at_ = |k: u32| v3(&pos[k as usize]);
    let ints: &[u32] = b.ints;
    // Each owner's pairs in the order the kernel's walk finds them (which slot a pair
    // takes; the kernel test compares the slots exactly).
    let found: Vec<Pair> = (0..l.num_owners())
        .into_par_iter()
        .with_min_len(b.min_len)
        .flat_map_iter(|o| {
            let mut found: Vec<Pair> = Vec::new();
            if o < l.np {
                // The search's own tests (`vt_pair`, `ee_pair`): the kernel's exact
                // distances, its early outs never dropping a pair within the reach.
                let x = at_(o as u32);
                query(ints, &l, pos, m, 0, [x, x], reach, 0, |t| {
                    found.extend(vt_pair(pos, m.triangles, o as u32, t, reach));
                });
            } else {
                let e = (o - l.np) as u32;
                let [a, bb] = m.edges[e as usize];
                let (p0, p1) = (at_(a), at_(bb));
                query(ints, &l, pos, m, 1, [p0.min(p1), p0.max(p1)], reach, e + 1, |g| {
                    found.extend(ee_pair(pos, m.edges, e, g, reach).map(|(_, g, d)| (o as u32, g, d)));
                });
            }
            found
        })
        .collect();
    keep_pairs(m, &found, b);
}

/// The second half of `tri_pairs`, whatever found the pairs: `found` is every pair
/// closer than the reach, `(owner, other, distance)` ([`vt_pair`]'s and [`ee_pair`]'s
/// distances; owners as numbered above, in increasing order). Each owner's
/// [`TRI_SLOTS`] nearest are kept (by distance, then index: in the slots where `found`'s
/// order leaves them, as the kernel's walk leaves its), its count of pairs written, each
/// vertex's bound lowered to the fraction of every pair's distance it belongs to, and the
/// pairs and those beyond the slots counted. The CPU solvers hand it the pairs kept
/// between searches (`crate::tri_pipeline::Contact`); the set of pairs, and so every
/// stage after it, is the same.
pub fn keep_pairs(m: Prims, found: &[Pair], b: &mut TriBufs) {
    let l = b.l;
    let slots = TRI_SLOTS as usize;
    // Where each owner's pairs start in `found`.
    let mut starts = vec![0u32; l.num_owners() + 1];
    for &(o, _, _) in found {
        starts[o as usize + 1] += 1;
    }
    for o in 0..l.num_owners() {
        starts[o + 1] += starts[o];
    }
    let (kept, near) = b.pairs.split_at_mut(l.num_owners() * slots);
    let counts = &mut b.ints[l.owners()..l.owners() + l.num_owners()];
    kept.par_chunks_mut(slots)
        .zip(near.par_chunks_mut(slots))
        .zip(counts.par_iter_mut())
        .enumerate()
        .with_min_len(b.min_len.max(64))
        .for_each(|(o, ((kept, near), count))| {
            let mine = &found[starts[o] as usize..starts[o + 1] as usize];
            for (n, &(_, other, d)) in mine.iter().enumerate() {
                if n < slots {
                    kept[n] = other;
                    near[n] = d.to_bits();
                } else {
                    // Full: the farthest kept gives way to a nearer (the kernel's walk).
                    let key = |k: usize| (f32::from_bits(near[k]), kept[k]);
                    let far = (1..slots).fold(0, |far, k| if farther(key(k), key(far)) { k } else { far });
                    if farther(key(far), (d, other)) {
                        kept[far] = other;
                        near[far] = d.to_bits();
                    }
                }
            }
            *count = mine.len() as u32;
        });
    for &(o, other, d) in found {
        for k in verts(m, &l, o as usize, other) {
            lower(b.floats, k, BOUND_FRACTION * d);
        }
    }
    let n = found.len() as u32;
    b.ints[at::PAIRS] += n;
    b.ints[at::OVERFLOW] +=
        (0..l.num_owners()).map(|o| (starts[o + 1] - starts[o]).saturating_sub(TRI_SLOTS)).sum::<u32>();
}

pub use crate::tri_pair::Pass;
use crate::tri_pair::{Response, Sides};

/// The vertices of owner `o`'s pair with primitive `other`: the vertex and the
/// triangle's, or both edges'.
fn verts(m: Prims, l: &TriLayout, o: usize, other: u32) -> [u32; 4] {
    if o < l.np {
        let [a, b, c] = m.triangles[other as usize];
        [o as u32, a, b, c]
    } else {
        let ([a, b], [c, d]) = (m.edges[o - l.np], m.edges[other as usize]);
        [a, b, c, d]
    }
}

/// Owner `o`'s pair with primitive `other`: a vertex and a triangle, or two edges.
fn sides(m: Prims, pos: &[V4], l: &TriLayout, o: usize, other: u32) -> Sides {
    if o < l.np {
        Sides::vertex_triangle(pos, o as u32, m.triangles[other as usize])
    } else {
        Sides::edge_edge(pos, m.edges[o - l.np], m.edges[other as usize])
    }
}

/// The pair's response (`clothlab_core::tri_contact`'s, with the inverse masses from `pos`'s w
/// and the step's thickness, substep and friction).
fn response(p: &StepParams, pos: &[V4], vel: &[V4], s: Sides, pass: Pass) -> Option<Response> {
    let mu = crate::tri_pair::Friction { stat: p.mu_static(), kinetic: p.mu_kinetic() };
    crate::tri_pair::response(s, |k| pos[k as usize][3], vel, p.self_thickness, p.dt, mu, pass)
}

/// The fixed point of a pass's sums.
fn unit(p: &StepParams, pass: Pass) -> f32 {
    match pass {
        Pass::Velocity => p.self_thickness * (1.0 / p.dt) * (1.0 / UNITS),
        Pass::Separation => p.self_thickness * (1.0 / UNITS),
    }
}

/// Every owner's kept pairs `(owner, other)`, owner by owner (what the passes and VBD's
/// terms walk: the CPU solvers list them once a substep).
pub(crate) fn kept_list(b: &TriBufs) -> Vec<(u32, u32)> {
    let (l, ints, pairs) = (b.l, &*b.ints, &*b.pairs);
    (0..l.num_owners())
        .into_par_iter()
        .with_min_len(b.min_len.max(1024))
        .flat_map_iter(|o| {
            let n = ints[l.owners() + o].min(TRI_SLOTS) as usize;
            pairs[o * TRI_SLOTS as usize..][..n].iter().map(move |&other| (o as u32, other))
        })
        .collect()
}

/// The response in `pass` at `pos` and `vel` of each of `pairs` (`(owner, other)`: the
/// kept pairs, [`kept_list`]) that has one (what the count and the share of a pass both
/// compute).
pub(crate) fn responses(
    p: &StepParams,
    m: Prims,
    pos: &[V4],
    vel: &[V4],
    b: &TriBufs,
    pairs: &[(u32, u32)],
    pass: Pass,
) -> Vec<Response> {
    let l = b.l;
    pairs
        .par_iter()
        .with_min_len(b.min_len.max(256))
        .filter_map(|&(o, other)| response(p, pos, vel, sides(m, pos, &l, o as usize, other), pass))
        .collect()
}

/// `tri_vbd`: the contact terms under VBD (`crate::tri_pair::vbd_terms`) of every kept
/// pair at `pos` (the sweep's iterate) for the vertices of colour `colour`
/// (`colour_of`: each particle's) that are not held, into their sums ([`TriLayout::vbd`]).
pub fn tri_vbd(p: &StepParams, m: Prims, colour_of: &[u32], pos: &[V4], colour: u32, b: &mut TriBufs) {
    let pairs = kept_list(b);
    add_vbd_terms(p, m, colour_of, pos, colour, &pairs, b);
}

/// The second half of [`tri_vbd`], over `pairs` `(owner, other)`: at least the kept
/// pairs with a vertex of the colour (the CPU solvers hand it each colour's, listed once
/// a substep by [`pairs_by_colour`]; a pair without one adds nothing).
pub(crate) fn add_vbd_terms(
    p: &StepParams,
    m: Prims,
    colour_of: &[u32],
    pos: &[V4],
    colour: u32,
    pairs: &[(u32, u32)],
    b: &mut TriBufs,
) {
    let wanted = crate::tri_pair::vbd_wanted(pos, colour_of, colour, p.grab_index);
    let (l, at) = (b.l, b.l.vbd());
    let words: Vec<(usize, u32)> = pairs
        .par_iter()
        .with_min_len(b.min_len.max(64))
        .flat_map_iter(|&(o, other)| {
            let mut words = Vec::new();
            if verts(m, &l, o as usize, other).iter().any(|&v| wanted(v)) {
                let s = sides(m, pos, &l, o as usize, other);
                crate::tri_pair::vbd_terms(&s, p.self_thickness, wanted, |i, v| words.push((i, v)));
            }
            words
        })
        .collect();
    for (i, v) in words {
        b.ints[at + i] = b.ints[at + i].wrapping_add(v);
    }
}

/// The kept pairs `kept` (`(owner, other)`, [`kept_list`]) with a vertex of each colour (`colour_of`: each
/// particle's), a list a colour.
pub(crate) fn pairs_by_colour(m: Prims, colour_of: &[u32], l: &TriLayout, kept: &[(u32, u32)]) -> Vec<Vec<(u32, u32)>> {
    let colours = colour_of.iter().copied().max().map_or(0, |c| c as usize + 1);
    let mut lists = vec![Vec::new(); colours];
    for &(o, other) in kept {
        let mut seen = [u32::MAX; 4];
        for (j, v) in verts(m, l, o as usize, other).into_iter().enumerate() {
            let c = colour_of[v as usize];
            if !seen[..j].contains(&c) {
                lists[c as usize].push((o, other));
            }
            seen[j] = c;
        }
    }
    lists
}

/// `tri_impulse_count` and `tri_separate_count`: each vertex's count of the pairs with a
/// response that move it (word 3 of its sums).
pub fn tri_count(p: &StepParams, m: Prims, pos: &[V4], vel: &[V4], b: &mut TriBufs, pass: Pass) {
    let r = responses(p, m, pos, vel, b, &kept_list(b), pass);
    count_responses(&r, b);
}

/// The count of [`tri_count`] from the pass's responses.
pub(crate) fn count_responses(responses: &[Response], b: &mut TriBufs) {
    let sums = b.l.sums();
    for k in responses.iter().flat_map(|r| r.acting()) {
        let w = &mut b.ints[sums + 4 * k as usize + 3];
        *w = w.wrapping_add(1);
    }
}

/// `tri_impulse_share` and `tri_separate_share`: each response spread over its vertices
/// (`clothlab_core::tri_contact`'s share: over the most pairs any of its vertices is in, by
/// inverse mass and weight), in fixed point into the sums; the responses counted.
pub fn tri_share(p: &StepParams, m: Prims, pos: &[V4], vel: &[V4], b: &mut TriBufs, pass: Pass) {
    let r = responses(p, m, pos, vel, b, &kept_list(b), pass);
    share_responses(p, pos, &r, b, pass);
}

/// The shares of [`tri_share`] from the pass's responses (counted by [`count_responses`]).
pub(crate) fn share_responses(p: &StepParams, pos: &[V4], responses: &[Response], b: &mut TriBufs, pass: Pass) {
    let (sums, u) = (b.l.sums(), unit(p, pass));
    let ints = &*b.ints;
    let adds: Vec<(u32, [i32; 3])> = responses
        .par_iter()
        .with_min_len(b.min_len.max(256))
        .flat_map_iter(|r| {
            let most = r.acting().map(|k| ints[sums + 4 * k as usize + 3]).max().unwrap_or(1);
            r.shares(most, |k| pos[k as usize][3], u)
        })
        .collect();
    for (k, d) in adds {
        for (c, dc) in d.iter().enumerate() {
            let w = &mut b.ints[sums + 4 * k as usize + c];
            *w = (*w as i32).wrapping_add(*dc) as u32;
        }
    }
    let stat = if pass == Pass::Velocity { at::SLOWED } else { at::PUSHED };
    b.ints[stat] += responses.len() as u32;
}

/// One pass (the velocity pass, or a separation pass) as the CPU runs it: its responses
/// found once for [`count_responses`] and [`share_responses`] (what `tri_*_count` and
/// `tri_*_share` each find), then [`tri_apply`].
pub(crate) fn run_pass(
    p: &StepParams,
    m: Prims,
    pos: &mut [V4],
    vel: &mut [V4],
    b: &mut TriBufs,
    pairs: &[(u32, u32)],
    pass: Pass,
) {
    let r = responses(p, m, pos, vel, b, pairs, pass);
    count_responses(&r, b);
    share_responses(p, pos, &r, b, pass);
    tri_apply(p, pos, vel, b, pass);
}

/// `tri_impulse_apply` and `tri_separate_apply`: each particle's sums added (the
/// velocity pass's to its velocity; the separation's to its position and, over dt, its
/// velocity), the sums cleared.
pub fn tri_apply(p: &StepParams, pos: &mut [V4], vel: &mut [V4], b: &mut TriBufs, pass: Pass) {
    let (sums, u) = (b.l.sums(), unit(p, pass));
    for (k, (x, v)) in pos.iter_mut().zip(vel.iter_mut()).enumerate() {
        let s = &mut b.ints[sums + 4 * k..sums + 4 * k + 4];
        for c in 0..3 {
            let d = crate::tri_pair::from_units(s[c] as i32, u);
            match pass {
                Pass::Velocity => v[c] += d,
                Pass::Separation => {
                    x[c] += d;
                    v[c] += d * (1.0 / p.dt);
                }
            }
        }
        s.fill(0);
    }
}

/// `tri_clamp_sum`: the free vertices' displacements since the start, in
/// `MEAN_UNIT`s, into the 64-bit sums (`clothlab_core::tri_contact::mean_displacement`), and
/// their count.
pub fn tri_clamp_sum(pos: &[V4], b: &mut TriBufs) {
    for (x, s) in pos.iter().zip(b.floats.iter()) {
        if x[3] <= 0.0 {
            continue;
        }
        for (c, units) in clothlab_core::tri_contact::mean_units(s, x).into_iter().enumerate() {
            let units = units as i64;
            let (lo, hi) = (at::MEAN + 2 * c, at::MEAN + 2 * c + 1);
            let sum = ((b.ints[hi] as u64) << 32 | b.ints[lo] as u64) as i64;
            let sum = sum.wrapping_add(units);
            (b.ints[lo], b.ints[hi]) = (sum as u32, (sum >> 32) as u32);
        }
        b.ints[at::FREE] += 1;
    }
}

/// The free vertices' mean displacement from the sums.
pub fn clamp_mean(ints: &[u32]) -> Vec3 {
    let sum = [0, 1, 2].map(|k| ((ints[at::MEAN + 2 * k + 1] as u64) << 32 | ints[at::MEAN + 2 * k] as u64) as i64);
    clothlab_core::tri_contact::mean_of_units(sum, ints[at::FREE])
}

/// `tri_clamp_check`: whether some vertex is farther than its bound from the mean
/// displacement, and whether some moved farther than its bound.
pub fn tri_clamp_check(pos: &[V4], b: &mut TriBufs) {
    let mean = clamp_mean(b.ints);
    for (x, s) in pos.iter().zip(b.floats.iter()) {
        let d = v3(x) - v3(s);
        // NaN compares false: over.
        let within = matches!(
            (d - mean).length().partial_cmp(&s[3]),
            Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal)
        );
        if !within {
            b.ints[at::OVER] = 1;
        }
        if d.length() > s[3] {
            b.ints[at::MOVED] = 1;
        }
    }
}

/// `tri_clamp`: where some vertex is over its bound from the mean, every vertex's motion
/// since the start cut to its bound, the cut taken from its velocity (over dt).
pub fn tri_clamp(p: &StepParams, pos: &mut [V4], vel: &mut [V4], b: &mut TriBufs) {
    if b.ints[at::OVER] == 0 {
        return;
    }
    let mut clamped = 0;
    for ((x, v), s) in pos.iter_mut().zip(vel.iter_mut()).zip(b.floats.iter()) {
        clamped += u32::from(crate::tri_pair::clamp_to_bound(x, v, v3(s), s[3], p.dt));
    }
    b.ints[at::CLAMPED] += clamped;
}

/// What the last substep did, from the scalars (`clothlab_core::solver::ContactStats`).
pub fn stats(ints: &[u32]) -> clothlab_core::solver::ContactStats {
    let spared = ints[at::OVER] == 0 && ints[at::MOVED] != 0;
    clothlab_core::solver::ContactStats {
        reach: f(ints[at::REACH]),
        pairs: ints[at::PAIRS] as usize,
        slowed: ints[at::SLOWED] as usize,
        pushed: ints[at::PUSHED] as usize,
        clamped: ints[at::CLAMPED] as usize,
        shared: if spared { clamp_mean(ints).length() } else { 0.0 },
        ..Default::default()
    }
}
