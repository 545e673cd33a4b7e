//! The closest points between two cloth primitives: a vertex and a triangle, two edges.
//! What contact between triangles is built from (docs/contact.md): a pair closer than the
//! thickness gets a contact at these points, along the normal from one to the other, its
//! response spread over the primitives' vertices by the weights returned here.

use glam::Vec3;
use rayon::prelude::*;

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
        let v = d1 / (d1 - d3);
        return PointTriangle { weights: [1.0 - v, v, 0.0], point: a + ab * v, region: Region::Edge(0) };
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return vertex(2, c);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return PointTriangle { weights: [1.0 - w, 0.0, w], point: a + ac * w, region: Region::Edge(2) };
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
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
        return at(0.0, (f / e).clamp(0.0, 1.0), false);
    }
    let c = d1.dot(r);
    if e == 0.0 {
        return at((-c / a).clamp(0.0, 1.0), 0.0, false);
    }
    let b = d1.dot(d2);
    let denom = a * e - b * b;
    if denom <= PARALLEL_SIN2 * a * e {
        // The overlap of q's projection on p, its middle, and the closest point of q to it.
        let s0 = ((q0 - p0).dot(d1) / a).clamp(0.0, 1.0);
        let s1 = ((q1 - p0).dot(d1) / a).clamp(0.0, 1.0);
        let s = 0.5 * (s0 + s1);
        let t = ((p0 + d1 * s - q0).dot(d2) / e).clamp(0.0, 1.0);
        return at(s, t, true);
    }
    let mut s = ((b * f - c * e) / denom).clamp(0.0, 1.0);
    let mut t = (b * s + f) / e;
    if t < 0.0 {
        t = 0.0;
        s = (-c / a).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((b - c) / a).clamp(0.0, 1.0);
    }
    at(s, t, false)
}

/// The fraction of its distance to the nearest primitive it shares no vertex with that a
/// vertex may move before contacts are found again (OGC's γ, VBD's truncation): under ½,
/// so that two primitives each moving less than it cannot meet.
pub const BOUND_FRACTION: f32 = 0.45;

/// The pairs of primitives that share no vertex and are closer than `reach`, of the cloth
/// with triangles `triangles` at `pos`: vertex–triangle pairs `(vertex, triangle,
/// distance)` and edge–edge pairs `(edge, edge, distance)` (each once, the first edge's
/// index lower), edges indexing `edges` — found through a grid of cells `reach` plus half
/// the longest edge wide, vertex by vertex and edge by edge in parallel.
pub struct NearPairs {
    /// The cloth's edges, each once ([`crate::crossings::edges`]).
    pub edges: Vec<[u32; 2]>,
    /// Vertex, triangle, distance.
    pub vt: Vec<(u32, u32, f32)>,
    /// Edge, edge, distance.
    pub ee: Vec<(u32, u32, f32)>,
}

/// [`NearPairs`] of `pos` within `reach`.
pub fn near_pairs(pos: &[crate::grid::V4], triangles: &[[u32; 3]], reach: f32) -> NearPairs {
    let at = |k: u32| Vec3::from_slice(&pos[k as usize][..3]);
    let edges = crate::crossings::edges(triangles);
    // A point of an edge is within a quarter of its length of its ends or its middle, where
    // the edge looks: a primitive within `reach` of it is within a cell of one of them.
    let longest = edges.iter().map(|&[a, b]| (at(a) - at(b)).length()).filter(|l| l.is_finite()).fold(0.0, f32::max);
    let cell = (reach + 0.5 * longest).max(1e-6);
    let key = |x: Vec3| {
        let c = (x / cell).floor();
        [c.x as i32, c.y as i32, c.z as i32]
    };
    // Each triangle and edge in the cells its box covers; a vertex looks in its own cell and
    // the 26 around it (a primitive within `reach` covers one of them).
    let mut grid: std::collections::HashMap<[i32; 3], (Vec<u32>, Vec<u32>)> = std::collections::HashMap::new();
    let mut insert = |ks: &[u32], id: u32, tri: bool| {
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for &k in ks {
            lo = lo.min(at(k));
            hi = hi.max(at(k));
        }
        if !(lo.is_finite() && hi.is_finite()) {
            return;
        }
        let (l, h) = (key(lo), key(hi));
        for i in l[0]..=h[0] {
            for j in l[1]..=h[1] {
                for k in l[2]..=h[2] {
                    let e = grid.entry([i, j, k]).or_default();
                    if tri { e.0.push(id) } else { e.1.push(id) }
                }
            }
        }
    };
    for (t, tri) in triangles.iter().enumerate() {
        insert(tri, t as u32, true);
    }
    for (e, edge) in edges.iter().enumerate() {
        insert(edge, e as u32, false);
    }
    // The triangles (`tri`) or edges near `xs`: those registered in the 27 cells around
    // each, once each, sorted.
    let around = |xs: &[Vec3], tri: bool| -> Vec<u32> {
        let mut ids = Vec::new();
        for &x in xs {
            let c = key(x);
            for i in -1..=1 {
                for j in -1..=1 {
                    for k in -1..=1 {
                        if let Some(cell) = grid.get(&[c[0] + i, c[1] + j, c[2] + k]) {
                            ids.extend_from_slice(if tri { &cell.0 } else { &cell.1 });
                        }
                    }
                }
            }
        }
        ids.sort_unstable();
        ids.dedup();
        ids
    };
    // Vertex–triangle pairs closer than `reach`, found vertex by vertex in parallel.
    let vt: Vec<(u32, u32, f32)> = (0..pos.len() as u32)
        .into_par_iter()
        .flat_map_iter(|v| {
            let x = at(v);
            let near = if x.is_finite() { around(&[x], true) } else { Vec::new() };
            near.into_iter().filter_map(move |t| {
                let tri = triangles[t as usize];
                if tri.contains(&v) {
                    return None;
                }
                let d = (point_triangle(x, at(tri[0]), at(tri[1]), at(tri[2])).point - x).length();
                (d < reach).then_some((v, t, d))
            })
        })
        .collect();
    // Edge–edge pairs closer than `reach` (each pair once: the second edge after the first).
    let edge_list = &edges;
    let ee: Vec<(u32, u32, f32)> = (0..edges.len() as u32)
        .into_par_iter()
        .flat_map_iter(|e| {
            let [a, b] = edge_list[e as usize];
            let (p0, p1) = (at(a), at(b));
            let near =
                if p0.is_finite() && p1.is_finite() { around(&[p0, p1, 0.5 * (p0 + p1)], false) } else { Vec::new() };
            near.into_iter().filter_map(move |f| {
                let [c, d] = edge_list[f as usize];
                if f <= e || c == a || c == b || d == a || d == b {
                    return None;
                }
                let r = edge_edge(p0, p1, at(c), at(d));
                let dist = (r.p - r.q).length();
                (dist < reach).then_some((e, f, dist))
            })
        })
        .collect();
    NearPairs { edges, vt, ee }
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
    let mut bound = vec![reach; pos.len()];
    let mut take = |ks: &[u32], d: f32| {
        for &k in ks {
            let b = &mut bound[k as usize];
            *b = b.min(d);
        }
    };
    let pairs = near_pairs(pos, triangles, reach);
    for &(v, t, d) in &pairs.vt {
        take(&[v], BOUND_FRACTION * d);
        take(&triangles[t as usize], BOUND_FRACTION * d);
    }
    for &(e, f, d) in &pairs.ee {
        let ([a, b], [c, dd]) = (pairs.edges[e as usize], pairs.edges[f as usize]);
        take(&[a, b, c, dd], BOUND_FRACTION * d);
    }
    bound.iter_mut().for_each(|b| *b = b.min(BOUND_FRACTION * reach));
    bound
}

/// One Jacobi pass of the contact between primitives: each pair of [`near_pairs`] closer
/// than `thickness` is pushed apart to it along the line between its closest points — the
/// constraint `n·(p − q) ≥ thickness` projected with the vertices' inverse masses
/// `inv_mass` (0: pinned) and the closest points' weights, so that the pair's momentum
/// does not change (its pushes weighted by mass sum to zero). Each vertex's pushes are
/// summed in fixed point ([`crate::cpu::self_collide::UNITS`] per thickness, truncated:
/// the same sum in any order, as the particle contact's). Writes the moved positions to
/// `out` and returns the pairs pushed.
pub fn separate(
    pos: &[crate::grid::V4],
    triangles: &[[u32; 3]],
    inv_mass: &[f32],
    thickness: f32,
    out: &mut [crate::grid::V4],
) -> usize {
    use crate::cpu::self_collide::UNITS;
    let at = |k: u32| Vec3::from_slice(&pos[k as usize][..3]);
    let pairs = near_pairs(pos, triangles, thickness);
    let unit = thickness / UNITS;
    let mut sum = vec![[0i64; 3]; pos.len()];
    let mut pushed = 0;
    // Pushes `scale · n` on each of `ks` (weights `ws`, the sign for the pair's side).
    let mut push = |ks: &[u32], ws: &[f32], sign: f32, n: Vec3, s: f32| {
        for (&k, &w) in ks.iter().zip(ws) {
            let d = n * (sign * inv_mass[k as usize] * w * s / unit);
            let acc = &mut sum[k as usize];
            for c in 0..3 {
                acc[c] += d[c] as i64;
            }
        }
    };
    // Projects one pair with points p (vertices `a`, weights `wa`) and q (`b`, `wb`).
    let mut pair = |a: &[u32], wa: &[f32], b: &[u32], wb: &[f32], p: Vec3, q: Vec3, fallback: Vec3| {
        let d = (p - q).length();
        let n = if d > 0.0 { (p - q) / d } else { fallback };
        let k: f32 = a.iter().zip(wa).chain(b.iter().zip(wb)).map(|(&v, &w)| inv_mass[v as usize] * w * w).sum();
        if k == 0.0 || !n.is_finite() {
            return;
        }
        let s = (thickness - d) / k;
        push(a, wa, 1.0, n, s);
        push(b, wb, -1.0, n, s);
        pushed += 1;
    };
    for &(v, t, _) in &pairs.vt {
        let [ta, tb, tc] = triangles[t as usize];
        let (x, a, b, c) = (at(v), at(ta), at(tb), at(tc));
        let r = point_triangle(x, a, b, c);
        pair(&[v], &[1.0], &[ta, tb, tc], &r.weights, x, r.point, (b - a).cross(c - a).normalize());
    }
    for &(e, f, _) in &pairs.ee {
        let ([a, b], [c, d]) = (pairs.edges[e as usize], pairs.edges[f as usize]);
        let r = edge_edge(at(a), at(b), at(c), at(d));
        let fallback = (at(b) - at(a)).cross(at(d) - at(c)).normalize();
        pair(&[a, b], &[1.0 - r.s, r.s], &[c, d], &[1.0 - r.t, r.t], r.p, r.q, fallback);
    }
    for (k, o) in out.iter_mut().enumerate() {
        let x = pos[k];
        *o = [x[0] + sum[k][0] as f32 * unit, x[1] + sum[k][1] as f32 * unit, x[2] + sum[k][2] as f32 * unit, x[3]];
    }
    pushed
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

    /// Σ of the moves of `out` from `pos` weighted by mass (1 / inverse mass; pinned left out).
    fn momentum(pos: &[crate::grid::V4], out: &[crate::grid::V4], inv_mass: &[f32]) -> Vec3 {
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
        let unit = t / crate::cpu::self_collide::UNITS;
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
        let pos = [
            [-1.0, 0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0, 1.0],
            [0.0, -1.0, 0.5 * t, 1.0],
            [0.0, 1.0, 0.5 * t, 1.0],
            [0.0, 0.0, 1.0, 1.0],
        ];
        let tris = [[0, 1, 2], [3, 4, 5]];
        let inv = [1.0; 6];
        let mut out = pos;
        separate(&pos, &tris, &inv, t, &mut out);
        let r = edge_edge(
            Vec3::from_slice(&out[0][..3]),
            Vec3::from_slice(&out[1][..3]),
            Vec3::from_slice(&out[3][..3]),
            Vec3::from_slice(&out[4][..3]),
        );
        // Four vertices pushed, each truncated by under a unit: 4 units.
        assert!(((r.p - r.q).length() - t).abs() < 4.0 * unit, "{:?}", r);
        // Four vertices of mass 1: under 4 units a component, 4√3 < 7 in length.
        assert!(momentum(&pos, &out, &inv).length() < 7.0 * unit);
        // Primitives that share a vertex are never pushed; nor are pairs farther than t.
        let pos = [[0.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0], [1.0, 1.0, 0.001, 1.0]];
        let mut out = pos;
        assert_eq!(separate(&pos, &[[0, 1, 2], [1, 3, 2]], &[1.0; 4], t, &mut out), 0);
        assert_eq!(out, pos);
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
