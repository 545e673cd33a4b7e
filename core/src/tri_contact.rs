//! The closest points between two cloth primitives: a vertex and a triangle, two edges.
//! What contact between triangles is built from (docs/contact.md): a pair closer than the
//! thickness gets a contact at these points, along the normal from one to the other, its
//! response spread over the primitives' vertices by the weights returned here.

use glam::Vec3;

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

#[cfg(test)]
mod tests {
    use super::*;

    const A: Vec3 = Vec3::new(0.0, 0.0, 0.0);
    const B: Vec3 = Vec3::new(1.0, 0.0, 0.0);
    const C: Vec3 = Vec3::new(0.0, 1.0, 0.0);

    #[test]
    fn a_point_finds_the_face_the_edge_or_the_vertex_it_is_nearest() {
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
    fn two_edges_find_their_closest_points_crossed_skew_and_parallel() {
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
