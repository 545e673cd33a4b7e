//! The contact between triangles as the CPU runs it (docs/contact.md): the stages of a
//! substep ([`Contact`]: the GPU kernels' twins of `crate::tri_contact` in the recipe's
//! order, each vertex's bound at the start, the approaches slowed, the pairs pushed
//! apart, every motion clamped to its bound at the end) with the pairs kept between
//! searches (what the twins compute of a pair is `crate::tri_pair`'s). The geometry it
//! is built from — closest points, the pair search, the bounds and the constants the
//! kernels share — is the model's (`clothlab_core::tri_contact`).

use glam::Vec3;
use rayon::prelude::*;

use clothlab_core::broad::BoxGrid;
use clothlab_core::grid::V4;
use clothlab_core::step_params::StepParams;
use clothlab_core::tri_contact::*;

use crate::tri_contact::{
    Pass, Prims, TriBufs, TriLayout, add_vbd_terms, at, keep_pairs, kept_list, pairs_by_colour, run_pass, stats,
    tri_clamp, tri_clamp_check, tri_clamp_sum, tri_speed, tri_start,
};

/// The pairs of the last search (within its reach at its positions) and what it needs
/// to tell whether they still hold every pair within a substep's reach.
///
/// Why they do: a point of a primitive is a weighted mean of its vertices, so relative to
/// any common motion `m` it has moved no farther than the farthest vertex (`δ = max |Δₖ −
/// m|`), and two primitives' distance has changed by at most 2δ since the search. A pair
/// within `r` now was within `r + 2δ` then: found by a search that looked as far, and the
/// boxes' test (each coordinate moves by at most δ relative to `m`) the same. The pairs
/// within `r` are then filtered from the kept ones with the search's own tests
/// (`boxes_meet`, [`vt_pair`], [`ee_pair`]): the same pairs, the same distances' bits,
/// so the contact computes what a search every substep computes.
#[derive(Debug, Clone, Default)]
struct Search {
    /// The positions it searched at.
    at: Vec<clothlab_core::grid::V4>,
    /// How far it looked.
    reach: f32,
    /// Its pairs: vertex–triangle and edge–edge, grouped by owner as [`find_pairs`]'s.
    vt: Vec<Pair>,
    ee: Vec<Pair>,
    /// Each vertex's [`drift`] at the last [`Search::covers`] (0 after a search, and for
    /// the vertices a partial search moved): a kept pair `d` apart at the search is at
    /// least `d − δ_P − δ_Q` apart, each `δ` the largest of its primitive's vertices'.
    drifts: Vec<f32>,
    scale: f32,
}

/// Each vertex's `|Δₖ − m|`, `Δₖ` its displacement from `from` to `to` and `m` their mean
/// (any common motion serves: [`Search`]), `m`, and the largest coordinate of `to` in
/// magnitude; a position that is not finite has an infinite one.
fn drift(from: &[clothlab_core::grid::V4], to: &[clothlab_core::grid::V4], min_len: usize) -> (Vec<f32>, Vec3, f32) {
    let delta = |k: usize| Vec3::from_slice(&to[k][..3]) - Vec3::from_slice(&from[k][..3]);
    let sum = (0..to.len())
        .into_par_iter()
        .with_min_len(min_len)
        .map(|k| delta(k).as_dvec3())
        .filter(|d| d.is_finite())
        .reduce(|| glam::DVec3::ZERO, |a, b| a + b);
    let mean = (sum / to.len().max(1) as f64).as_vec3();
    let drifts: Vec<f32> = (0..to.len())
        .into_par_iter()
        .with_min_len(min_len)
        .map(|k| {
            let d = (delta(k) - mean).length();
            if d.is_finite() && Vec3::from_slice(&to[k][..3]).is_finite() { d } else { f32::INFINITY }
        })
        .collect();
    let scale = to.iter().map(|x| Vec3::from_slice(&x[..3]).abs().max_element()).fold(0.0, f32::max);
    (drifts, mean, scale)
}

/// What the kept pairs need at a substep ([`Search::covers`]).
enum Cover {
    /// Nothing: they hold every pair within the reach.
    Holds,
    /// The pairs of these vertices' primitives found again (the rest hold).
    Refresh(Vec<bool>),
    /// A new search.
    Search,
}

/// A partial search refreshes at most this fraction of the vertices; more make a search.
const REFRESH_MOST: f32 = 0.25;

impl Search {
    /// Whether the kept pairs hold every pair within `reach` at `pos`: `reach + δ_P + δ_Q`
    /// within the search's reach for every two primitives (each `δ` the largest [`drift`]
    /// of its vertices, with room for the distances' rounding). Where only some vertices
    /// drifted too far, those vertices' snapshot is moved to where they are (less the
    /// mean motion) and their primitives' pairs are to be found again ([`Cover::Refresh`]).
    fn covers(&mut self, pos: &[clothlab_core::grid::V4], reach: f32, min_len: usize) -> Cover {
        if self.at.len() != pos.len() || reach.is_nan() || reach >= self.reach {
            return Cover::Search;
        }
        let (drifts, mean, scale) = drift(&self.at, pos, min_len);
        self.scale = scale;
        // A distance's rounding: a few ulps of the coordinates and of the reach.
        let slack = 1e-6 * scale + 1e-5 * self.reach;
        let limit = 0.5 * (self.reach - reach - slack);
        let most = drifts.iter().copied().fold(0.0, f32::max);
        if limit.is_nan() || limit <= 0.0 || !most.is_finite() {
            return Cover::Search;
        }
        if most <= limit {
            self.drifts = drifts;
            return Cover::Holds;
        }
        // Those over half the limit, so that the rest have room for a few substeps more.
        let fast: Vec<bool> = drifts.iter().map(|&d| d > 0.5 * limit).collect();
        let count = fast.iter().filter(|&&f| f).count();
        if count as f32 > REFRESH_MOST * pos.len() as f32 {
            return Cover::Search;
        }
        for (k, _) in fast.iter().enumerate().filter(|(_, f)| **f) {
            for c in 0..3 {
                self.at[k][c] = pos[k][c] - mean[c];
            }
        }
        self.drifts = drifts.iter().zip(&fast).map(|(&d, &f)| if f { 0.0 } else { d }).collect();
        Cover::Refresh(fast)
    }

    /// The pairs within the search's reach of the primitives with a vertex in `fast`,
    /// found again at the snapshot (whose `fast` vertices [`Search::covers`] moved): every
    /// other pair's distance there is as it was.
    fn refresh(&mut self, fast: &[bool], triangles: &[[u32; 3]], edges: &[[u32; 2]]) {
        let (at, reach) = (&self.at[..], self.reach);
        let point = |k: u32| Vec3::from_slice(&at[k as usize][..3]);
        let tri_fast: Vec<bool> = triangles.iter().map(|t| t.iter().any(|&k| fast[k as usize])).collect();
        let edge_fast: Vec<bool> = edges.iter().map(|e| e.iter().any(|&k| fast[k as usize])).collect();
        self.vt.retain(|&(v, t, _)| !fast[v as usize] && !tri_fast[t as usize]);
        self.ee.retain(|&(e, f, _)| !edge_fast[e as usize] && !edge_fast[f as usize]);
        let list =
            |flags: &[bool]| flags.iter().enumerate().filter(|(_, f)| **f).map(|(k, _)| k as u32).collect::<Vec<u32>>();
        let (tris, edge_grid, cell) = box_grids(at, triangles, edges, reach);
        let points = BoxGrid::new(cell, at.len(), |k| std::iter::once(point(k as u32)));
        // A fast vertex against every triangle; a fast triangle against the other vertices.
        let mut vt = vertex_pairs(at, triangles, &tris, list(fast).into_par_iter().with_min_len(16), reach);
        vt.par_extend(list(&tri_fast).into_par_iter().with_min_len(16).flat_map_iter(|t| {
            let b = clothlab_core::broad::bounds(triangles[t as usize].iter().map(|&k| point(k)));
            let mut found = Vec::new();
            points.query(b, reach, 0, |v| {
                if !fast[v as usize] {
                    found.extend(vt_pair(at, triangles, v, t, reach));
                }
            });
            found
        }));
        // A fast edge against every other (each pair once: from the lower fast edge).
        let mut ee: Vec<Pair> = list(&edge_fast)
            .into_par_iter()
            .with_min_len(16)
            .flat_map_iter(|e| {
                let [a, b] = edges[e as usize];
                let (p0, p1) = (point(a), point(b));
                let mut found = Vec::new();
                edge_grid.query([p0.min(p1), p0.max(p1)], reach, 0, |f| {
                    if f != e && !(edge_fast[f as usize] && f < e) {
                        found.extend(ee_pair(at, edges, e.min(f), e.max(f), reach));
                    }
                });
                found
            })
            .collect();
        let by_owner = |p: &Pair| (p.0, p.1);
        vt.par_sort_unstable_by_key(by_owner);
        ee.par_sort_unstable_by_key(by_owner);
        self.vt = merge(std::mem::take(&mut self.vt), vt, by_owner);
        self.ee = merge(std::mem::take(&mut self.ee), ee, by_owner);
    }

    /// The kept pairs within `reach` at `pos`: what [`find_pairs`] finds there, in the
    /// same order of owners.
    fn within(
        &self,
        pos: &[clothlab_core::grid::V4],
        triangles: &[[u32; 3]],
        edges: &[[u32; 2]],
        reach: f32,
        min_len: usize,
    ) -> (Vec<Pair>, Vec<Pair>) {
        let at = |k: u32| Vec3::from_slice(&pos[k as usize][..3]);
        let finite = |b: [Vec3; 2]| b[0].is_finite() && b[1].is_finite();
        // The kept pairs that pass `test`, those that cannot have come within the reach
        // since the search ruled out first: `moved(o, k)` is how much nearer the pair may
        // have come (its two primitives' largest drifts: most vertices drift far less than
        // the fastest, so this rules out more than twice the largest drift).
        let drift = |ks: &[u32]| ks.iter().map(|&k| self.drifts[k as usize]).fold(0.0, f32::max);
        let keep = |list: &[Pair],
                    moved: &(dyn Fn(u32, u32) -> f32 + Sync),
                    test: &(dyn Fn(u32, u32) -> Option<Pair> + Sync)|
         -> Vec<Pair> {
            list.par_iter()
                .with_min_len(min_len)
                .filter_map(
                    |&(o, k, d)| if surely_beyond(d - moved(o, k), reach, self.scale) { None } else { test(o, k) },
                )
                .collect()
        };
        let vt_moved = |v: u32, t: u32| self.drifts[v as usize] + drift(&triangles[t as usize]);
        let ee_moved = |e: u32, f: u32| drift(&edges[e as usize]) + drift(&edges[f as usize]);
        let vt = keep(&self.vt, &vt_moved, &|v, t| {
            let x = at(v);
            let tri = clothlab_core::broad::bounds(triangles[t as usize].iter().map(|&k| at(k)));
            (finite([x, x]) && finite(tri) && clothlab_core::broad::boxes_meet(tri, [x, x], reach))
                .then(|| vt_pair(pos, triangles, v, t, reach))
                .flatten()
        });
        let ee = keep(&self.ee, &ee_moved, &|e, f| {
            let [a, b] = edges[e as usize];
            let (p0, p1) = (at(a), at(b));
            let eb = [p0.min(p1), p0.max(p1)];
            let fb = clothlab_core::broad::bounds(edges[f as usize].iter().map(|&k| at(k)));
            (finite(eb) && finite(fb) && clothlab_core::broad::boxes_meet(fb, eb, reach))
                .then(|| ee_pair(pos, edges, e, f, reach))
                .flatten()
        });
        (vt, ee)
    }
}

/// The contact between triangles as the CPU solvers run it (docs/contact.md, the CPU
/// solver's `Stage::Triangle*`): the GPU kernels' twins (`crate::tri_contact`) on
/// buffers of the kernels' layout, in the recipe's order — one implementation of each
/// stage. What differs is only how the pairs are found: a GPU walks its grid every
/// substep; here a search's pairs within its reach and a margin are kept and serve the
/// substeps after it until a vertex has drifted too far (docs/contact.md), and
/// `tri_contact::keep_pairs` makes of either the same owners' slots, so every stage
/// after computes the same bits.
///
/// At the substep's start each vertex's bound on its motion and the velocity pass
/// ([`Contact::begin`]); after the integrator the pairs closer than the thickness pushed
/// apart ([`Contact::separate`]); at the end every vertex's motion since the start
/// clamped to its bound ([`Contact::clamp`]), whatever moved it — the integrator, the
/// separation, the colliders, the strain limit. So a state without crossings keeps none
/// under every integrator. The velocity takes each move (`Δx/dt`, as the strain limit's
/// does).
#[derive(Debug, Clone, Default)]
pub struct Contact {
    /// Search and run the stages on rayon's threads (`Exec::Parallel`); else on one.
    pub parallel: bool,
    edges: Vec<[u32; 2]>,
    /// The kernels' buffers ([`TriLayout`]): each particle's start and bound, the
    /// integers, the pairs.
    layout: Option<TriLayout>,
    floats: Vec<V4>,
    ints: Vec<u32>,
    pairs: Vec<u32>,
    /// The last search's pairs, which serve the substeps until a vertex has moved too far.
    search: Search,
    /// The substep's kept pairs with a vertex of each colour (VBD's terms), listed at the
    /// first colour's terms after each [`Contact::begin`].
    by_colour: Vec<Vec<(u32, u32)>>,
    /// The substep's kept pairs `(owner, other)` (`tri_contact::kept_list`), listed once
    /// for the passes and VBD's terms.
    kept: Vec<(u32, u32)>,
    searches: u64,
    refreshes: u64,
}

/// A search's pairs (vertex–triangle `vt`, edge–edge `ee`, each grouped by owner) as
/// `keep_pairs` takes them: owners as the kernels number them, the `np` vertices, then
/// the edges.
fn by_owner(np: usize, vt: Vec<Pair>, ee: Vec<Pair>) -> Vec<Pair> {
    let np = np as u32;
    vt.into_iter().chain(ee.into_iter().map(|(e, f, d)| (np + e, f, d))).collect()
}

impl Contact {
    /// The stages' buffers for the cloths of `triangles`.
    pub fn new(triangles: &[[u32; 3]], parallel: bool) -> Self {
        Self { parallel, edges: clothlab_core::crossings::edges(triangles), ..Self::default() }
    }

    /// The pairs (or vertices) a task of the search takes on rayon's threads.
    fn pass_len(&self) -> usize {
        if self.parallel { 256 } else { usize::MAX }
    }

    /// The primitives, the kernels' buffers (sized for `np` particles) and the kept pairs.
    fn parts<'a>(&'a mut self, triangles: &'a [[u32; 3]], np: usize) -> (Prims<'a>, TriBufs<'a>, &'a mut Search) {
        let l = TriLayout::new(np, triangles.len(), self.edges.len());
        if self.layout != Some(l) {
            self.layout = Some(l);
            self.floats = vec![[0.0; 4]; np];
            self.ints = vec![0; l.words()];
            self.pairs = vec![0; l.pair_words()];
        }
        let min_len = if self.parallel { 1 } else { usize::MAX };
        let b = TriBufs { l, floats: &mut self.floats, ints: &mut self.ints, pairs: &mut self.pairs, min_len };
        (Prims { triangles, edges: &self.edges }, b, &mut self.search)
    }

    /// At the substep's start (`tri_speed`, `tri_start`, the pairs, the velocity pass): the
    /// reach from the fastest vertex (`tri_contact::reach_of`), the positions kept, each
    /// vertex's bound, and the approach of every pair within the reach that would close
    /// to under the thickness in this substep slowed to what closes it to the thickness
    /// (with Coulomb friction). The pairs are the kept ones where they still hold every
    /// pair within the reach (no vertex drifted too far since), else a search's within the reach and
    /// `margin` spacings more.
    pub fn begin(&mut self, p: &StepParams, pos: &mut [V4], vel: &mut [V4], triangles: &[[u32; 3]], margin: f32) {
        let (parallel, min_len) = (self.parallel, self.pass_len());
        let (mut searched, mut refreshed) = (0, 0);
        let (m, mut b, search) = self.parts(triangles, pos.len());
        b.ints.fill(0);
        tri_speed(pos, vel, &mut b);
        tri_start(p, pos, &mut b);
        let reach = f32::from_bits(b.ints[at::REACH]);
        match search.covers(pos, reach, min_len) {
            Cover::Holds => {}
            Cover::Refresh(fast) => {
                search.refresh(&fast, m.triangles, m.edges);
                refreshed = 1;
            }
            Cover::Search => {
                let far = reach + margin * p.spacing;
                let (vt, ee) = find_pairs(pos, m.triangles, m.edges, far, parallel);
                let scale = pos.iter().map(|x| Vec3::from_slice(&x[..3]).abs().max_element()).fold(0.0, f32::max);
                *search = Search { at: pos.to_vec(), reach: far, vt, ee, drifts: vec![0.0; pos.len()], scale };
                searched = 1;
            }
        }
        let (vt, ee) = search.within(pos, m.triangles, m.edges, reach, min_len);
        keep_pairs(m, &by_owner(pos.len(), vt, ee), &mut b);
        let kept = kept_list(&b);
        run_pass(p, m, pos, vel, &mut b, &kept, Pass::Velocity);
        self.kept = kept;
        self.by_colour.clear();
        self.searches += searched;
        self.refreshes += refreshed;
    }

    /// [`SEPARATION_PASSES`] passes of the separation (`tri_separate_*`) on `pos` over
    /// the pairs of the substep's start (within the reach, which is at least the
    /// thickness) that are now closer than the thickness, each pass's moves added to `vel`
    /// too (over the substep). No second search: a pair that came within the thickness
    /// from beyond the reach in this substep is pushed in the next (the bounds keep it
    /// from crossing meanwhile).
    pub fn separate(&mut self, p: &StepParams, pos: &mut [V4], vel: &mut [V4], triangles: &[[u32; 3]]) {
        let kept = std::mem::take(&mut self.kept);
        let (m, mut b, _) = self.parts(triangles, pos.len());
        for _ in 0..SEPARATION_PASSES {
            run_pass(p, m, pos, vel, &mut b, &kept, Pass::Separation);
        }
        self.kept = kept;
    }

    /// VBD's contact terms (`tri_vbd`) of the pairs of the substep's start at `pos` (the
    /// sweep's iterate, `x⁰ + D`) for the vertices of colour `colour` (`colour_of`: each
    /// particle's) that are not held (pinned, or the grabbed one): what
    /// `cpu::vbd::vbd_colour` adds to their blocks ([`Contact::vbd_sums`]), and clears.
    pub fn vbd_terms(&mut self, p: &StepParams, pos: &[V4], triangles: &[[u32; 3]], colour_of: &[u32], colour: u32) {
        let mut lists = std::mem::take(&mut self.by_colour);
        let kept = std::mem::take(&mut self.kept);
        let (m, mut b, _) = self.parts(triangles, pos.len());
        if lists.is_empty() {
            lists = pairs_by_colour(m, colour_of, &b.l, &kept);
        }
        let pairs = lists.get(colour as usize).map_or(&[][..], |l| &l[..]);
        add_vbd_terms(p, m, colour_of, pos, colour, pairs, &mut b);
        self.by_colour = lists;
        self.kept = kept;
    }

    /// The terms [`Contact::vbd_terms`] left ([`VBD_TERMS`] words a particle), for
    /// `cpu::vbd::vbd_colour` (which clears its colour's).
    pub fn vbd_sums(&mut self) -> &mut [u32] {
        match self.layout {
            Some(l) => &mut self.ints[l.vbd()..l.words()],
            None => &mut [],
        }
    }

    /// Every vertex's motion since [`Contact::begin`] cut to its bound, the cut taken
    /// from its velocity too (over the substep) — unless the cloths move as one
    /// (`tri_clamp_sum`, `tri_clamp_check`, `tri_clamp`): measured from the free
    /// vertices' mean displacement (summed in fixed point: the same bits in any order),
    /// no vertex over its bound. A displacement all vertices share changes no distance,
    /// so the bounds hold in that frame too and nothing is cut: two sheets falling
    /// together are not slowed, however fast. (Cutting in the mean's frame where some
    /// vertex is over it was tried: the thin heap's landed half was dragged into the
    /// floor's margin and its closest pair came to 0.42 of the thickness instead of
    /// 0.93; each vertex's own motion is cut instead.)
    pub fn clamp(&mut self, p: &StepParams, pos: &mut [V4], vel: &mut [V4], triangles: &[[u32; 3]]) {
        let (_, mut b, _) = self.parts(triangles, pos.len());
        tri_clamp_sum(pos, &mut b);
        tri_clamp_check(pos, &mut b);
        tri_clamp(p, pos, vel, &mut b);
    }

    /// Each vertex's bound of the last [`Contact::begin`].
    pub fn bounds(&self) -> Vec<f32> {
        self.floats.iter().map(|x| x[3]).collect()
    }

    /// What the last substep's stages did (`tri_contact::stats`) and how the pairs were
    /// found: what [`clothlab_core::Solver::contact_stats`] reports.
    pub fn stats(&self) -> clothlab_core::solver::ContactStats {
        let outcome = if self.ints.is_empty() { Default::default() } else { stats(&self.ints) };
        clothlab_core::solver::ContactStats {
            searches: self.searches,
            refreshes: self.refreshes,
            kept: self.search.vt.len() + self.search.ee.len(),
            ..outcome
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const A: Vec3 = Vec3::new(0.0, 0.0, 0.0);
    const B: Vec3 = Vec3::new(1.0, 0.0, 0.0);
    const C: Vec3 = Vec3::new(0.0, 1.0, 0.0);

    #[test]
    fn a_point_finds_the_face_the_edge_or_the_vertex_it_is_nearest() {
        // Bounds here: a few f32 roundings of values of order 1 (ε = 1.2e-7): 1e-7 where
        // the result is one or two operations, 1e-6 where it is a sum of several products.
        // Above the face: the foot of the perpendicular, its weights the coordinates.
        let f = point_triangle(Vec3::new(0.25, 0.25, 0.3), A, B, C);
        assert_eq!(f.region, Region::Face);
        assert!((f.point - Vec3::new(0.25, 0.25, 0.0)).length() < 1e-7, "{f:?}");
        assert!((f.weights[0] - 0.5).abs() < 1e-7 && (f.weights[1] - 0.25).abs() < 1e-7);
        // Beyond each edge: its foot on the edge.
        let e0 = point_triangle(Vec3::new(0.3, -0.5, 0.1), A, B, C);
        assert_eq!((e0.region, e0.point), (Region::Edge(0), Vec3::new(0.3, 0.0, 0.0)));
        let e1 = point_triangle(Vec3::new(1.0, 1.0, 0.0), A, B, C);
        assert_eq!(e1.region, Region::Edge(1));
        assert!((e1.point - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-7, "{e1:?}");
        let e2 = point_triangle(Vec3::new(-0.5, 0.6, 0.0), A, B, C);
        assert_eq!((e2.region, e2.point), (Region::Edge(2), Vec3::new(0.0, 0.6, 0.0)));
        // Beyond each vertex: the vertex.
        for (p, k, v) in
            [(Vec3::new(-1.0, -1.0, 0.5), 0, A), (Vec3::new(2.0, -0.5, 0.0), 1, B), (Vec3::new(-0.1, 2.0, 0.0), 2, C)]
        {
            let r = point_triangle(p, A, B, C);
            assert_eq!((r.region, r.point), (Region::Vertex(k), v));
            assert_eq!(r.weights[k as usize], 1.0);
        }
        // The weights always rebuild the point.
        for p in [Vec3::new(0.1, 0.7, -0.2), Vec3::new(0.9, 0.9, 1.0), Vec3::new(0.4, -0.1, 0.0)] {
            let r = point_triangle(p, A, B, C);
            let rebuilt = A * r.weights[0] + B * r.weights[1] + C * r.weights[2];
            assert!((rebuilt - r.point).length() < 1e-6 && (r.weights.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn a_bound_is_the_fraction_of_the_nearest_pair_a_vertex_belongs_to() {
        // A triangle and, 0.2 above its face, a small one: its corner over the face is 0.2 from
        // it (vertex–triangle), which bounds every vertex of both; every other pair (the
        // big one's corners, the edges) is farther apart.
        let pos = [
            [0.0, 0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0, 1.0],
            [0.0, 1.0, 0.0, 1.0],
            [0.2, 0.2, 0.2, 1.0],
            [0.3, 0.2, 0.2, 1.0],
            [0.3, 0.3, 0.2, 1.0],
        ];
        let b = motion_bounds(&pos, &[[0, 1, 2], [3, 4, 5]], 1.0);
        for (k, b) in b.iter().enumerate() {
            assert!((b - BOUND_FRACTION * 0.2).abs() < 1e-6, "vertex {k}: {b}");
        }
        // Beyond the reach, only the reach bounds them.
        let b = motion_bounds(&pos, &[[0, 1, 2], [3, 4, 5]], 0.1);
        assert!(b.iter().all(|&b| b == BOUND_FRACTION * 0.1), "{b:?}");
    }

    /// Two lone triangles whose nearest edges (0–1 along x, 3–4 along y) cross `gap` apart
    /// in z, inverse masses 1.
    fn crossed_edges(gap: f32) -> Vec<clothlab_core::grid::V4> {
        vec![
            [-1.0, 0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0, 1.0],
            [0.0, -1.0, gap, 1.0],
            [0.0, 1.0, gap, 1.0],
            [0.0, 0.0, 1.0, 1.0],
        ]
    }

    /// The distance between edges 0–1 and 3–4 of `pos`.
    fn edges_gap(pos: &[clothlab_core::grid::V4]) -> f32 {
        let at = |k: usize| Vec3::from_slice(&pos[k][..3]);
        let r = edge_edge(at(0), at(1), at(3), at(4));
        (r.p - r.q).length()
    }

    /// A step's constants with the contact's thickness `t`, substep `dt` and rest
    /// `spacing` (no gravity, no friction, nothing grabbed).
    fn consts(t: f32, dt: f32, spacing: f32) -> StepParams {
        StepParams { dt, self_thickness: t, spacing, grab_index: -1, ..bytemuck::Zeroable::zeroed() }
    }

    /// One separation pass (the `tri_separate_*` twins) over the pairs closer than `t` at
    /// `pos`, the vertices' inverse masses `inv`: the moved positions into `out` (their w
    /// as `pos`'s); returns the pairs pushed.
    fn separate(pos: &[V4], tris: &[[u32; 3]], inv: &[f32], t: f32, out: &mut [V4]) -> usize {
        let edges = clothlab_core::crossings::edges(tris);
        let m = Prims { triangles: tris, edges: &edges };
        let l = TriLayout::new(pos.len(), tris.len(), edges.len());
        let (mut floats, mut ints, mut pairs) = (vec![[0.0; 4]; l.np], vec![0; l.words()], vec![0; l.pair_words()]);
        let mut b = TriBufs { l, floats: &mut floats, ints: &mut ints, pairs: &mut pairs, min_len: usize::MAX };
        for ((o, x), &w) in out.iter_mut().zip(pos).zip(inv) {
            *o = [x[0], x[1], x[2], w];
        }
        let (vt, ee) = find_pairs(out, tris, &edges, t, false);
        keep_pairs(m, &by_owner(pos.len(), vt, ee), &mut b);
        let mut vel = vec![[0.0; 4]; pos.len()];
        let kept = kept_list(&b);
        run_pass(&consts(t, 1.0, 1.0), m, out, &mut vel, &mut b, &kept, Pass::Separation);
        for (o, x) in out.iter_mut().zip(pos) {
            o[3] = x[3];
        }
        b.ints[at::PUSHED] as usize
    }

    /// Σ of the moves of `out` from `pos` weighted by mass (1 / inverse mass; pinned left out).
    fn momentum(pos: &[clothlab_core::grid::V4], out: &[clothlab_core::grid::V4], inv_mass: &[f32]) -> Vec3 {
        pos.iter()
            .zip(out)
            .zip(inv_mass)
            .filter(|(_, w)| **w > 0.0)
            .map(|((a, b), w)| (Vec3::from_slice(&b[..3]) - Vec3::from_slice(&a[..3])) / *w)
            .sum()
    }

    #[test]
    fn a_vertex_and_a_triangle_or_two_edges_closer_than_the_thickness_are_pushed_to_it_momentum_kept() {
        let t = 0.01;
        let unit = t / clothlab_core::tables::CONTACT_UNITS;
        // A vertex 0.4 t above a triangle's centroid, masses 1 (inverse mass 1) and, for the
        // triangle's vertices, 2 (0.5): its plane and the vertex end t apart, the pushes
        // weighted by mass sum to zero (to the fixed point's truncation, a unit a vertex).
        let c = Vec3::new(1.0 / 3.0, 1.0 / 3.0, 0.0);
        let pos = [
            [0.0, 0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0, 1.0],
            [0.0, 1.0, 0.0, 1.0],
            [c.x, c.y, 0.4 * t, 1.0],
            [c.x, c.y, 0.9, 1.0],
            [c.x + 0.1, c.y, 0.9, 1.0],
        ];
        let tris = [[0, 1, 2], [3, 4, 5]];
        let inv = [0.5, 0.5, 0.5, 1.0, 1.0, 1.0];
        let mut out = pos;
        assert_eq!(separate(&pos, &tris, &inv, t, &mut out), 1);
        let plane_z = (out[0][2] + out[1][2] + out[2][2]) / 3.0;
        // Each of the four pushed vertices truncates its push by under a unit: 4 units.
        assert!((out[3][2] - plane_z - t).abs() < 4.0 * unit, "gap {} for {t}", out[3][2] - plane_z);
        // Each push truncates by under a unit a component: three vertices of mass 2 and one
        // of 1 leave under 7 units a component, 7√3 < 12.2 in length.
        assert!(momentum(&pos, &out, &inv).length() < 12.2 * unit, "{:?}", momentum(&pos, &out, &inv));
        // The triangle pinned: the vertex goes the whole way.
        let pinned = [0.0, 0.0, 0.0, 1.0, 1.0, 1.0];
        separate(&pos, &tris, &pinned, t, &mut out);
        // One push, truncated by under a unit, plus the gap's own rounding: 2 units.
        assert!((out[3][2] - t).abs() < 2.0 * unit && out[0] == pos[0], "{:?}", out[3]);
        // Two edges crossed 0.5 t apart (two lone triangles whose nearest edges cross): each
        // edge moves half the gap.
        let pos = crossed_edges(0.5 * t);
        let tris = [[0, 1, 2], [3, 4, 5]];
        let inv = [1.0; 6];
        let mut out = pos.clone();
        separate(&pos, &tris, &inv, t, &mut out);
        // Four vertices pushed, each truncated by under a unit: 4 units.
        let gap = edges_gap(&out);
        assert!((gap - t).abs() < 4.0 * unit, "gap {gap}");
        // Four vertices of mass 1: under 4 units a component, 4√3 < 7 in length.
        assert!(momentum(&pos, &out, &inv).length() < 7.0 * unit);
        // Primitives that share a vertex are never pushed; nor are pairs farther than t.
        let pos = [[0.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0], [1.0, 1.0, 0.001, 1.0]];
        let mut out = pos;
        assert_eq!(separate(&pos, &[[0, 1, 2], [1, 3, 2]], &[1.0; 4], t, &mut out), 0);
        assert_eq!(out, pos);
    }

    /// `steps` substeps through the contact stages: the bounds and the velocity pass, in
    /// the first substep a velocity change `kick` (z, m/s) on vertices 3.. (a shove the
    /// velocity pass does not see, as the integrator's force), the motion, the separation,
    /// the clamp. Returns the
    /// positions after each and the vertices the clamp cut in all.
    fn fly(
        pos: &mut [clothlab_core::grid::V4],
        vel: &mut [clothlab_core::grid::V4],
        tris: &[[u32; 3]],
        (t, dt, kick): (f32, f32, f32),
        steps: usize,
    ) -> (Vec<Vec<clothlab_core::grid::V4>>, usize) {
        let mut c = Contact::new(tris, false);
        let p = consts(t, dt, 1.0);
        let (mut path, mut clamped) = (Vec::new(), 0);
        for step in 0..steps {
            c.begin(&p, pos, vel, tris, 0.5);
            if step == 0 {
                for v in &mut vel[3..] {
                    v[2] += kick;
                }
            }
            for (x, v) in pos.iter_mut().zip(vel.iter()) {
                for k in 0..3 {
                    x[k] += v[k] * dt;
                }
            }
            c.separate(&p, pos, vel, tris);
            c.clamp(&p, pos, vel, tris);
            clamped += c.stats().clamped;
            path.push(pos.to_vec());
        }
        (path, clamped)
    }

    /// Σ m v of `vel` (masses 1 / `pos`'s inverse mass).
    fn total_momentum(pos: &[clothlab_core::grid::V4], vel: &[clothlab_core::grid::V4]) -> Vec3 {
        pos.iter().zip(vel).map(|(x, v)| Vec3::from_slice(&v[..3]) / x[3]).sum()
    }

    #[test]
    fn a_vertex_thrown_at_a_triangle_stops_a_thickness_from_it_with_the_momentum_kept() {
        // A triangle at rest in z = 0 (vertices of mass 2) and a lone triangle of mass-1
        // vertices above it, one corner pointing down at its centroid, thrown down at 0.2
        // thickness a substep: slow enough that no bound cuts the motion (the clamp is not
        // an internal force), so the separation alone stops it.
        let (t, dt) = (0.01f32, 1e-3f32);
        let c = [1.0 / 3.0, 1.0 / 3.0];
        let mut pos = vec![
            [0.0, 0.0, 0.0, 0.5],
            [1.0, 0.0, 0.0, 0.5],
            [0.0, 1.0, 0.0, 0.5],
            [c[0], c[1], 0.05, 1.0],
            [c[0] - 0.1, c[1], 0.3, 1.0],
            [c[0] + 0.1, c[1], 0.3, 1.0],
        ];
        let speed = 0.2 * t / dt;
        let mut vel = vec![[0.0; 4]; 6];
        for v in &mut vel[3..] {
            v[2] = -speed;
        }
        let tris = [[0, 1, 2], [3, 4, 5]];
        let before = total_momentum(&pos, &vel);
        let steps = 60;
        let (path, clamped) = fly(&mut pos, &mut vel, &tris, (t, dt, 0.0), steps);
        assert_eq!(clamped, 0, "the bounds cut a motion of 0.2 t a substep");
        // The gap (the corner above the plane of the lower triangle) never under the
        // thickness by more than a substep's approach, and ends at it: within 1e-3 t (f32
        // positions near 1 m round by 6e-8 m a step, the fixed point by t/65536 a push).
        let gap = |p: &[clothlab_core::grid::V4]| p[3][2] - (p[0][2] + p[1][2] + p[2][2]) / 3.0;
        for (k, p) in path.iter().enumerate() {
            assert!(gap(p) > 0.79 * t, "substep {k}: gap {} for t = {t}", gap(p));
        }
        let end = gap(&path[steps - 1]);
        assert!((end - t).abs() < 1e-3 * t, "final gap {end} for t = {t}");
        // Σ m v: each push of a vertex truncates under one unit (t / 65536) a component, four
        // vertices a contact: under 4 units over dt a component per substep in contact.
        let after = total_momentum(&pos, &vel);
        let unit_rate = t / clothlab_core::tables::CONTACT_UNITS / dt;
        let bound = (steps as f32) * 4.0 * unit_rate * 2.0 * 3f32.sqrt();
        assert!((after - before).length() < bound, "momentum {before} -> {after} (bound {bound})");
        // The lower triangle took the corner's approach: it moves down now.
        assert!(vel[0][2] < -0.01 * speed, "{:?}", vel[0]);
    }

    #[test]
    fn an_edge_thrown_or_pushed_at_an_edge_ten_thicknesses_a_substep_never_passes() {
        // Two lone triangles whose nearest edges cross 5 thicknesses apart, the upper one
        // thrown down at 0.2 t a substep, thrown at 10 t (twice the gap in a substep), and
        // shoved to 10 t a substep within the first substep, where the velocity pass does
        // not see it (a force, as the integrator's). Thrown, slowly or fast, the velocity
        // pass stops the edges t apart with the momentum kept and no cut (thrown fast, the
        // pair then moves on as one at the mean velocity, which the bounds do not cut);
        // shoved, the bounds cut the motion, the edges never pass each other, and the gap
        // ends at t.
        let (t, dt) = (0.01f32, 1e-3f32);
        let start = crossed_edges(5.0 * t);
        let tris = [[0, 1, 2], [3, 4, 5]];
        let unit_rate = t / clothlab_core::tables::CONTACT_UNITS / dt;
        // (speed, kick, substeps): 8 substeps of the fast ones, before the upper apex (not
        // in the contact, still flying at 10 t a substep) reaches the lower triangle.
        for (speed, kick, steps) in [(0.2f32, 0.0f32, 60), (10.0, 0.0, 8), (0.0, 10.0, 8)] {
            let mut pos = start.clone();
            let mut vel = vec![[0.0; 4]; 6];
            for v in &mut vel[3..] {
                v[2] = -speed * t / dt;
            }
            let before = total_momentum(&pos, &vel);
            let (path, clamped) = fly(&mut pos, &mut vel, &tris, (t, dt, -kick * t / dt), steps);
            // The upper edge (3–4) stays above the lower (0–1): their z at the crossing.
            for (k, p) in path.iter().enumerate() {
                let gap = 0.5 * (p[3][2] + p[4][2]) - 0.5 * (p[0][2] + p[1][2]);
                assert!(gap > 0.0, "speed {speed} kick {kick}: the edges passed at substep {k} ({gap})");
            }
            let gap = edges_gap(&pos);
            println!("speed {speed} t, kick {kick} t a substep: gap {:.3} t, {clamped} cut", gap / t);
            if kick == 0.0 {
                assert_eq!(clamped, 0, "speed {speed}");
                // As in the test above: 1e-3 t, and 4 units over dt a substep of momentum.
                assert!((gap - t).abs() < 1e-3 * t, "speed {speed}: final gap {gap}");
                let bound = steps as f32 * 4.0 * unit_rate * 3f32.sqrt();
                assert!((total_momentum(&pos, &vel) - before).length() < bound, "speed {speed}");
            } else {
                // The cut is not an internal force: the momentum is not kept. What the test
                // holds: the bounds cut, and the pair ends no closer than t (1 % for the
                // fixed point and f32).
                assert!(clamped > 0, "the bounds never cut a motion of 10 t a substep");
                assert!(gap > 0.99 * t, "final gap {gap} for t = {t}");
            }
        }
    }

    #[test]
    fn two_edges_find_their_closest_points_crossed_skew_and_parallel() {
        // (Bounds: f32 roundings of values of order 1, as in the test above.)
        // Crossed 0.2 apart: the middles.
        let r = edge_edge(
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, -1.0, 0.2),
            Vec3::new(0.0, 1.0, 0.2),
        );
        assert!(!r.parallel && (r.s - 0.5).abs() < 1e-7 && (r.t - 0.5).abs() < 1e-7, "{r:?}");
        assert!(((r.p - r.q).length() - 0.2).abs() < 1e-6);
        // Skew with the nearest point past the second's end: clamped to it, the first's
        // parameter recomputed for it.
        let r = edge_edge(
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.5, 0.3, 0.0),
            Vec3::new(0.5, 1.0, 1.0),
        );
        assert_eq!((r.t, r.p), (0.0, Vec3::new(0.5, 0.0, 0.0)), "{r:?}");
        // Parallel, overlapping on x = 0.5 … 1: the overlap's middle, 0.1 apart.
        let r = edge_edge(
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.5, 0.1, 0.0),
            Vec3::new(1.5, 0.1, 0.0),
        );
        assert!(r.parallel, "{r:?}");
        assert!(
            (r.p - Vec3::new(0.75, 0.0, 0.0)).length() < 1e-6 && (r.q - Vec3::new(0.75, 0.1, 0.0)).length() < 1e-6,
            "{r:?}"
        );
        // A point and a segment.
        let r = edge_edge(Vec3::new(0.3, 1.0, 0.0), Vec3::new(0.3, 1.0, 0.0), Vec3::ZERO, Vec3::X);
        assert_eq!((r.s, r.q), (0.0, Vec3::new(0.3, 0.0, 0.0)));
    }
}
