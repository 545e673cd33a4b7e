//! The closest points between two cloth primitives: a vertex and a triangle, two edges.
//! What contact between triangles is built from (docs/contact.md): a pair closer than the
//! thickness gets a contact at these points, along the normal from one to the other, its
//! response spread over the primitives' vertices by the weights returned here.

use glam::Vec3;
use rayon::prelude::*;

use crate::broad::BoxGrid;

/// Where on a triangle (a, b, c) the closest point lies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Region {
    /// Inside the face.
    Face,
    /// On edge 0 (a–b), 1 (b–c) or 2 (c–a).
    Edge(u8),
    /// At vertex 0 (a), 1 (b) or 2 (c).
    Vertex(u8),
}

/// The closest point of a triangle to a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointTriangle {
    /// Its barycentric weights on (a, b, c): non-negative, summing to 1.
    pub weights: [f32; 3],
    /// The point.
    pub point: Vec3,
    /// Which feature it lies on.
    pub region: Region,
}

/// The closest point of triangle (a, b, c) to `p`, by the Voronoi regions of its vertices,
/// edges and face (Ericson, *Real-Time Collision Detection*, 5.1.5): the region found
/// first is the one the point lies in, so a point on the boundary of two gets the
/// vertex's or the edge's.
pub fn point_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> PointTriangle {
    let vertex = |k: u8, point: Vec3| {
        let mut weights = [0.0; 3];
        weights[k as usize] = 1.0;
        PointTriangle { weights, point, region: Region::Vertex(k) }
    };
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return vertex(0, a);
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return vertex(1, b);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 * (1.0 / (d1 - d3));
        return PointTriangle { weights: [1.0 - v, v, 0.0], point: a + ab * v, region: Region::Edge(0) };
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return vertex(2, c);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 * (1.0 / (d2 - d6));
        return PointTriangle { weights: [1.0 - w, 0.0, w], point: a + ac * w, region: Region::Edge(2) };
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) * (1.0 / ((d4 - d3) + (d5 - d6)));
        return PointTriangle { weights: [0.0, 1.0 - w, w], point: b + (c - b) * w, region: Region::Edge(1) };
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    PointTriangle { weights: [1.0 - v - w, v, w], point: a + ab * v + ac * w, region: Region::Face }
}

/// The closest points of two segments.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeEdge {
    /// The point's parameter on the first segment, 0 ..= 1.
    pub s: f32,
    /// The point's parameter on the second, 0 ..= 1.
    pub t: f32,
    /// The point on the first.
    pub p: Vec3,
    /// The point on the second.
    pub q: Vec3,
    /// The segments are parallel (to within 1e-3 rad): every point of their overlap is as
    /// close, and the points are the overlap's middle.
    pub parallel: bool,
}

/// sin² of the angle under which two segments count as parallel.
const PARALLEL_SIN2: f32 = 1e-6;

/// The closest points of segments p0–p1 and q0–q1 (Ericson 5.1.9), with the parallel case
/// taken at the middle of the overlap (a contact that does not jump from end to end as the
/// segments turn by a rounding error). A segment of zero length is its point.
pub fn edge_edge(p0: Vec3, p1: Vec3, q0: Vec3, q1: Vec3) -> EdgeEdge {
    let (d1, d2, r) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, e, f) = (d1.dot(d1), d2.dot(d2), d2.dot(r));
    let at = |s: f32, t: f32, parallel: bool| EdgeEdge { s, t, p: p0 + d1 * s, q: q0 + d2 * t, parallel };
    if a == 0.0 && e == 0.0 {
        return at(0.0, 0.0, false);
    }
    if a == 0.0 {
        return at(0.0, (f * (1.0 / e)).clamp(0.0, 1.0), false);
    }
    let c = d1.dot(r);
    if e == 0.0 {
        return at((-c * (1.0 / a)).clamp(0.0, 1.0), 0.0, false);
    }
    let b = d1.dot(d2);
    let denom = a * e - b * b;
    if denom <= PARALLEL_SIN2 * a * e {
        // The overlap of q's projection on p, its middle, and the closest point of q to it.
        let s0 = ((q0 - p0).dot(d1) * (1.0 / a)).clamp(0.0, 1.0);
        let s1 = ((q1 - p0).dot(d1) * (1.0 / a)).clamp(0.0, 1.0);
        let s = 0.5 * (s0 + s1);
        let t = ((p0 + d1 * s - q0).dot(d2) * (1.0 / e)).clamp(0.0, 1.0);
        return at(s, t, true);
    }
    let mut s = ((b * f - c * e) * (1.0 / denom)).clamp(0.0, 1.0);
    let mut t = (b * s + f) * (1.0 / e);
    if t < 0.0 {
        t = 0.0;
        s = (-c * (1.0 / a)).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((b - c) * (1.0 / a)).clamp(0.0, 1.0);
    }
    at(s, t, false)
}

/// The fraction of its distance to the nearest primitive it shares no vertex with that a
/// vertex may move before contacts are found again (OGC's γ, VBD's truncation): under ½,
/// so that two primitives each moving less than it cannot meet.
pub const BOUND_FRACTION: f32 = 0.45;

/// The reach per unit of the fastest vertex's motion in a substep: 1.25 / [`BOUND_FRACTION`]
/// (a product by this constant on every backend: a division by a constant may be compiled
/// as a product by its reciprocal, a last bit off).
pub const REACH_PER_MOTION: f32 = 1.25 / BOUND_FRACTION;

/// A pair of primitives: vertex and triangle, or edge and edge; and their distance.
pub type Pair = (u32, u32, f32);

/// The pairs of primitives that share no vertex and are closer than `reach`, of the cloth
/// with triangles `triangles` (and their `edges`, each once: [`crate::crossings::edges`])
/// at `pos`: vertex–triangle pairs `(vertex, triangle, distance)` and edge–edge pairs
/// `(edge, edge, distance)` (each once, the first edge's index lower). The triangles' and
/// the edges' boxes in two grids of cells (`BoxGrid`)
/// twice the reach or 1.5 mean edges wide (the larger: the fastest of 0.6, 1, 1.5 and 2.5
/// on the five-sheet stack; with each box listed once, 0.5 to 3 mean edges all within
/// 1.2× of it, 1 to 2 within the noise), each vertex's and edge's box grown by `reach`
/// looked up in them, vertex by vertex and edge by edge (in parallel with `parallel`).
pub fn find_pairs(
    pos: &[crate::grid::V4],
    triangles: &[[u32; 3]],
    edges: &[[u32; 2]],
    reach: f32,
    parallel: bool,
) -> (Vec<Pair>, Vec<Pair>) {
    let min_len = if parallel { 1 } else { usize::MAX };
    let at = |k: u32| Vec3::from_slice(&pos[k as usize][..3]);
    let (tris, edge_grid, _) = box_grids(pos, triangles, edges, reach);
    // Vertex–triangle pairs closer than `reach`, vertex by vertex.
    let vt = vertex_pairs(pos, triangles, &tris, (0..pos.len() as u32).into_par_iter().with_min_len(min_len), reach);
    // Edge–edge pairs closer than `reach` (each pair once: the second edge after the first).
    let ee: Vec<(u32, u32, f32)> = (0..edges.len() as u32)
        .into_par_iter()
        .with_min_len(min_len)
        .flat_map_iter(|e| {
            let [a, b] = edges[e as usize];
            let (p0, p1) = (at(a), at(b));
            let mut found = Vec::new();
            let eb = [p0.min(p1), p0.max(p1)];
            edge_grid.query(eb, reach, e + 1, |f| found.extend(ee_pair(pos, edges, e, f, reach)));
            found
        })
        .collect();
    (vt, ee)
}

/// The triangles' and the edges' boxes at `pos` in two grids of cells twice the reach or
/// 1.5 mean edges wide (the larger; [`find_pairs`]), and that width.
pub fn box_grids(
    pos: &[crate::grid::V4],
    triangles: &[[u32; 3]],
    edges: &[[u32; 2]],
    reach: f32,
) -> (BoxGrid, BoxGrid, f32) {
    let at = |k: u32| Vec3::from_slice(&pos[k as usize][..3]);
    let cell = (2.0 * reach).max(1.5 * mean_edge(pos, edges)).max(1e-6);
    let tris = BoxGrid::new(cell, triangles.len(), |t| triangles[t].iter().map(|&k| at(k)));
    let edge_grid = BoxGrid::new(cell, edges.len(), |e| edges[e].iter().map(|&k| at(k)));
    (tris, edge_grid, cell)
}

/// The vertex–triangle pairs within `reach` at `pos` of the vertices `owners` (on rayon's
/// threads as the iterator splits), each found in the triangles' grid `tris`; grouped by
/// vertex in the owners' order.
pub fn vertex_pairs(
    pos: &[crate::grid::V4],
    triangles: &[[u32; 3]],
    tris: &BoxGrid,
    owners: impl IndexedParallelIterator<Item = u32>,
    reach: f32,
) -> Vec<Pair> {
    owners
        .flat_map_iter(|v| {
            let x = Vec3::from_slice(&pos[v as usize][..3]);
            let mut found = Vec::new();
            tris.query([x, x], reach, 0, |t| found.extend(vt_pair(pos, triangles, v, t, reach)));
            found
        })
        .collect()
}

/// Vertex `v` and triangle `t` at `pos` as a pair of [`find_pairs`] within `reach`, once
/// their boxes meet: none where the triangle holds the vertex or the closest points are
/// `reach` or more apart.
pub fn vt_pair(pos: &[crate::grid::V4], triangles: &[[u32; 3]], v: u32, t: u32, reach: f32) -> Option<Pair> {
    let at = |k: u32| Vec3::from_slice(&pos[k as usize][..3]);
    let tri = triangles[t as usize];
    if tri.contains(&v) {
        return None;
    }
    let (x, a, b, c) = (at(v), at(tri[0]), at(tri[1]), at(tri[2]));
    // Every point of the triangle lies in its box, and within its corners' farthest from
    // their mean.
    let scale = x.abs().max(a.abs()).max(b.abs()).max(c.abs()).max_element();
    if surely_beyond(box_gap([x, x], [a.min(b).min(c), a.max(b).max(c)]), reach, scale) {
        return None;
    }
    let mid = (a + b + c) * (1.0 / 3.0);
    let radius = (a - mid).length().max((b - mid).length()).max((c - mid).length());
    if surely_beyond((x - mid).length() - radius, reach, scale) {
        return None;
    }
    let d = (point_triangle(x, a, b, c).point - x).length();
    (d < reach).then_some((v, t, d))
}

/// Whether a lower bound `lower` on a distance, computed from points whose largest
/// coordinate is `scale`, puts it at `reach` or beyond even if every rounding in it and in
/// the exact distance went the other way (a relative 1e-4 of the reach, and 1e-6 of the
/// coordinates: hundreds of ulps of either). A pair it rules out is never within the
/// reach, so the exact test that it saves would have refused it too.
pub fn surely_beyond(lower: f32, reach: f32, scale: f32) -> bool {
    lower >= reach * 1.0001 + 1e-6 * scale
}

/// The distance between two boxes (0 where they meet): no point of one is nearer a point
/// of the other. Where a grid's box test (per axis) lets two boxes meet across a corner
/// or an edge of their grown boxes, this rules them out before the closest points.
pub fn box_gap(a: [Vec3; 2], b: [Vec3; 2]) -> f32 {
    (b[0] - a[1]).max(a[0] - b[1]).max(Vec3::ZERO).length()
}

/// Edges `e` and `f` at `pos` as a pair of [`find_pairs`] within `reach`, once their
/// boxes meet: none where they share a vertex or are `reach` or more apart.
pub fn ee_pair(pos: &[crate::grid::V4], edges: &[[u32; 2]], e: u32, f: u32, reach: f32) -> Option<Pair> {
    let at = |k: u32| Vec3::from_slice(&pos[k as usize][..3]);
    let ([a, b], [c, d]) = (edges[e as usize], edges[f as usize]);
    if c == a || c == b || d == a || d == b {
        return None;
    }
    let (p0, p1, q0, q1) = (at(a), at(b), at(c), at(d));
    // Every point of a segment lies in its box, and within half its length of its middle.
    let scale = p0.abs().max(p1.abs()).max(q0.abs()).max(q1.abs()).max_element();
    if surely_beyond(box_gap([p0.min(p1), p0.max(p1)], [q0.min(q1), q0.max(q1)]), reach, scale) {
        return None;
    }
    let (mp, mq) = ((p0 + p1) * 0.5, (q0 + q1) * 0.5);
    let lower = (mp - mq).length() - 0.5 * ((p1 - p0).length() + (q1 - q0).length());
    if surely_beyond(lower, reach, scale) {
        return None;
    }
    let r = edge_edge(p0, p1, q0, q1);
    let dist = (r.p - r.q).length();
    (dist < reach).then_some((e, f, dist))
}

/// Two lists sorted by `key` as one.
pub fn merge(a: Vec<Pair>, b: Vec<Pair>, key: impl Fn(&Pair) -> (u32, u32)) -> Vec<Pair> {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut a, mut b) = (a.into_iter().peekable(), b.into_iter().peekable());
    while let (Some(x), Some(y)) = (a.peek(), b.peek()) {
        out.push(if key(x) <= key(y) { a.next() } else { b.next() }.expect("peeked"));
    }
    out.extend(a);
    out.extend(b);
    out
}

/// The mean length of `edges` at `pos` (those of finite length; 0 if none).
pub fn mean_edge(pos: &[crate::grid::V4], edges: &[[u32; 2]]) -> f32 {
    let at = |k: u32| Vec3::from_slice(&pos[k as usize][..3]);
    let (sum, count) = edges
        .iter()
        .map(|&[a, b]| (at(a) - at(b)).length())
        .filter(|l| l.is_finite())
        .fold((0.0f64, 0usize), |(s, n), l| (s + l as f64, n + 1));
    if count > 0 { (sum / count as f64) as f32 } else { 0.0 }
}

/// The smallest distance between a vertex and a triangle or two edges that share no vertex
/// in `pos`, looked for within two mean edges (that if none is nearer).
pub fn closest_pair(pos: &[crate::grid::V4], triangles: &[[u32; 3]]) -> f32 {
    let edges = crate::crossings::edges(triangles);
    let reach = 2.0 * mean_edge(pos, &edges);
    if reach <= 0.0 {
        return f32::INFINITY;
    }
    let (vt, ee) = find_pairs(pos, triangles, &edges, reach, true);
    vt.iter().chain(&ee).map(|p| p.2).fold(reach, f32::min)
}

/// How far each vertex of the cloth with triangles `triangles` at `pos` may move before
/// any two primitives that share no vertex could meet: [`BOUND_FRACTION`] of the smallest
/// distance between such a pair that it belongs to — a vertex and a triangle, or two
/// edges — and at most that fraction of `reach` (pairs farther apart are not looked for).
///
/// Why it holds: every point of a primitive is a weighted mean of its vertices, so it
/// moves no more than the farthest-moving vertex. Two primitives `d` apart whose vertices
/// each move less than γ·d (each vertex's bound is at most γ times the distance of every
/// pair it belongs to) close in by less than 2γ·d < d: they do not meet, and a primitive
/// cannot pass through another without meeting it.
pub fn motion_bounds(pos: &[crate::grid::V4], triangles: &[[u32; 3]], reach: f32) -> Vec<f32> {
    let mut bound = Vec::new();
    let _ = bounds_into(pos, triangles, &crate::crossings::edges(triangles), reach, true, &mut bound);
    bound
}

/// [`motion_bounds`] with the triangles' `edges` given, into `bound`; returns the pairs
/// within reach (vertex–triangle plus edge–edge).
pub fn bounds_into(
    pos: &[crate::grid::V4],
    triangles: &[[u32; 3]],
    edges: &[[u32; 2]],
    reach: f32,
    parallel: bool,
    bound: &mut Vec<f32>,
) -> (Vec<Pair>, Vec<Pair>) {
    let (vt, ee) = find_pairs(pos, triangles, edges, reach, parallel);
    bounds_of(pos.len(), &Pairs { triangles, edges, vt: &vt, ee: &ee }, reach, bound);
    (vt, ee)
}

/// Each of `np` vertices' bound into `bound`: [`BOUND_FRACTION`] of the nearest of
/// `pairs` (all the pairs within `reach`) it belongs to, at most that fraction of `reach`.
pub fn bounds_of(np: usize, pairs: &Pairs, reach: f32, bound: &mut Vec<f32>) {
    bound.clear();
    bound.resize(np, BOUND_FRACTION * reach);
    let mut take = |ks: &[u32], d: f32| {
        for &k in ks {
            let b = &mut bound[k as usize];
            *b = b.min(BOUND_FRACTION * d);
        }
    };
    for &(v, t, d) in pairs.vt {
        take(&[v], d);
        take(&pairs.triangles[t as usize], d);
    }
    for &(e, f, d) in pairs.ee {
        let ([a, b], [c, dd]) = (pairs.edges[e as usize], pairs.edges[f as usize]);
        take(&[a, b, c, dd], d);
    }
}

/// Pairs of primitives found by [`find_pairs`], with the triangles and edges they index.
pub struct Pairs<'a> {
    /// The cloths' triangles.
    pub triangles: &'a [[u32; 3]],
    /// Their edges, each once.
    pub edges: &'a [[u32; 2]],
    /// Vertex, triangle, distance.
    pub vt: &'a [(u32, u32, f32)],
    /// Edge, edge, distance.
    pub ee: &'a [(u32, u32, f32)],
}

/// Words a particle of VBD's contact terms (`vbd_terms`): the force's x, y, z, then the
/// block's six entries `[h00, h11, h22, h01, h02, h12]`, each a fixed-point sum.
pub const VBD_TERMS: usize = 9;

/// The pairs an owner acts on at most (a vertex its vertex–triangle pairs, an edge its
/// edge–edge pairs with the edges numbered above it): the nearest, by distance then
/// index — a set that does not depend on the search's order, so the GPU's fixed slots
/// (the layout's `TRI_SLOTS`, this number) hold the same pairs. The bounds see every pair.
pub const PAIRS_PER_OWNER: usize = 32;

/// Passes of the separation a substep (over the pairs found once): each pair's push is
/// shared among the pairs its vertices are in, so one pass leaves a pile short of the
/// thickness.
pub const SEPARATION_PASSES: usize = 4;

/// The reach of the bounds at most, in spacings beyond the thickness (the scene's rest
/// spacing: a grid's, a mesh's mean edge): a vertex alone may move [`BOUND_FRACTION`] of
/// the reach in a substep, and a larger reach finds more pairs.
pub const MAX_REACH_SPACINGS: f32 = 2.0;

/// The fixed point of [`mean_displacement`]'s sums, m: a power of two, so that a
/// displacement becomes units exactly before it is truncated (2⁻²⁴ m; a vertex's
/// displacement saturates at 128 m a substep).
pub const MEAN_UNIT: f32 = 1.0 / 16_777_216.0;

/// The free vertices' (w > 0) mean displacement from `start` to `pos`: each component
/// in [`MEAN_UNIT`]s truncated to 32 bits (saturating), summed in 64 bits (wrapping: a
/// GPU's pair of 32-bit atomics with a carry), the sum's high and low words to f32 and
/// back to metres over the count — the same bits in any order and on every backend.
pub fn mean_displacement(start: &[crate::grid::V4], pos: &[crate::grid::V4]) -> Vec3 {
    let (mut sum, mut count) = ([0i64; 3], 0u32);
    for (a, b) in start.iter().zip(pos) {
        if b[3] > 0.0 {
            for (s, u) in sum.iter_mut().zip(mean_units(a, b)) {
                *s = s.wrapping_add(u as i64);
            }
            count += 1;
        }
    }
    mean_of_units(sum, count)
}

/// A vertex's displacement from `a` to `b` in [`MEAN_UNIT`]s, truncated: what
/// [`mean_displacement`] and the `tri_clamp_sum` kernel add for it.
pub fn mean_units(a: &crate::grid::V4, b: &crate::grid::V4) -> [i32; 3] {
    [0, 1, 2].map(|c| ((b[c] - a[c]) / MEAN_UNIT) as i32)
}

/// The mean of `count` displacements from the sums of their [`mean_units`] (64-bit, as
/// the kernel keeps them in two words each).
pub fn mean_of_units(sum: [i64; 3], count: u32) -> Vec3 {
    let mean = |s: i64| {
        ((s >> 32) as i32 as f32 * 4_294_967_296.0 + s as u32 as f32) * MEAN_UNIT * (1.0 / count.max(1) as f32)
    };
    Vec3::new(mean(sum[0]), mean(sum[1]), mean(sum[2]))
}
