//! Where cloth passes through cloth: the edge–triangle intersections of a state between
//! elements that share no vertex (an edge through a triangle of the same cloth away from
//! it, or of another cloth). A layered cloth has none; each place where one sheet has gone
//! through another has some (a surface crossing a surface along a curve is cut by the
//! edges along that curve). What `sim` prints and the tests count.
//!
//! The test is in f64 (the positions are f32: their differences are exact or nearly, so a
//! sign is wrong only for a vertex within about 1e-16 m of the other element's plane or
//! edge line). An edge that only touches a triangle — an end on its plane, the segment
//! through its edge or corner — does not count: a crossing is a strict one.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::broad::{BoxGrid, bounds};
use crate::grid::V4;

/// The crossings of a state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Crossings {
    /// Edge–triangle pairs that share no vertex where the edge passes through the triangle.
    pub pairs: usize,
    /// Edges tested (each triangle's, once).
    pub edges: usize,
}

pub use crate::tables::edges;

fn p(pos: &[V4], k: u32) -> DVec3 {
    let x = pos[k as usize];
    DVec3::new(x[0] as f64, x[1] as f64, x[2] as f64)
}

/// The sign of the volume of (a, b, c, d): positive when d is on the side of the plane
/// (a, b, c) that its normal (b − a) × (c − a) points to.
fn orient(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    (b - a).cross(c - a).dot(d - a)
}

/// Whether segment (p, q) passes strictly through triangle (a, b, c).
pub fn segment_crosses_triangle(p: DVec3, q: DVec3, a: DVec3, b: DVec3, c: DVec3) -> bool {
    let sp = orient(a, b, c, p);
    let sq = orient(a, b, c, q);
    if !(sp > 0.0 && sq < 0.0 || sp < 0.0 && sq > 0.0) {
        return false;
    }
    // The line through p and q passes inside the triangle: it turns the same way around
    // each of the triangle's edges.
    let u = orient(p, q, a, b);
    let v = orient(p, q, b, c);
    let w = orient(p, q, c, a);
    u > 0.0 && v > 0.0 && w > 0.0 || u < 0.0 && v < 0.0 && w < 0.0
}

/// The crossings of the cloth with triangles `triangles` at positions `pos` (one or several
/// cloths in one list: a scene's state), found through a grid of cells about an edge long.
pub fn count(pos: &[V4], triangles: &[[u32; 3]]) -> Crossings {
    let edges = edges(triangles);
    if edges.is_empty() {
        return Crossings::default();
    }
    let at = |k: u32| Vec3::from_slice(&pos[k as usize][..3]);
    // Cells the size of the mean edge: a triangle's box covers a few of them. The boxes
    // are exact (the positions' own f32 extremes), so an edge through a triangle always
    // meets the triangle's box; the grid only skips pairs that cannot cross.
    let mean = edges.iter().map(|&[a, b]| (p(pos, a) - p(pos, b)).length()).sum::<f64>() / edges.len() as f64;
    let cell = if mean.is_finite() && mean > 0.0 { mean as f32 } else { 1.0 };
    let grid = BoxGrid::new(cell, triangles.len(), |t| triangles[t].iter().map(|&k| at(k)));
    let pairs = edges
        .par_iter()
        .map(|e| {
            // A box that is not finite meets nothing: neither does a NaN edge.
            let b = bounds(e.iter().map(|&k| at(k)));
            let (ep, eq) = (p(pos, e[0]), p(pos, e[1]));
            let mut crossed: usize = 0;
            grid.query(b, 0.0, 0, |t| {
                let tri = triangles[t as usize];
                if tri.contains(&e[0]) || tri.contains(&e[1]) {
                    return;
                }
                let [a, bb, c] = tri;
                if segment_crosses_triangle(ep, eq, p(pos, a), p(pos, bb), p(pos, c)) {
                    crossed += 1;
                }
            });
            crossed
        })
        .sum();
    Crossings { pairs, edges: edges.len() }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f32, y: f32, z: f32) -> V4 {
        [x, y, z, 1.0]
    }

    #[test]
    fn a_triangle_through_another_crosses_it_with_the_two_edges_that_pierce_it() {
        // T1 in the plane z = 0; T2 stands through it: its two edges from (0, 0, −1) pass
        // z = 0 at (0.15, 0) and (0, 0.15), inside T1; its top edge stays at z = 1, and T1's
        // edges (at x = −1, y = −1, x + y = 1) miss T2, which spans x + y ≤ 0.3 there.
        let pos = [
            v(-1.0, -1.0, 0.0),
            v(2.0, -1.0, 0.0),
            v(-1.0, 2.0, 0.0),
            v(0.0, 0.0, -1.0),
            v(0.3, 0.0, 1.0),
            v(0.0, 0.3, 1.0),
        ];
        let tris = [[0, 1, 2], [3, 4, 5]];
        assert_eq!(count(&pos, &tris), Crossings { pairs: 2, edges: 6 });
        // Lifted above T1 it crosses nothing; an end resting on T1's plane touches, not crosses.
        let lifted: Vec<V4> =
            pos.iter().enumerate().map(|(k, x)| if k >= 3 { [x[0], x[1], x[2] + 1.0, 1.0] } else { *x }).collect();
        assert_eq!(count(&lifted, &tris).pairs, 0);
    }

    #[test]
    fn triangles_that_share_a_vertex_never_count_and_a_flat_or_folded_sheet_has_none() {
        // A 6 × 6 sheet, flat, then folded along a row into a V of 60° (adjacent triangles
        // meet at an angle: no crossing), then with two rows pushed through it.
        let n = 6u32;
        let mut tris = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let k = j * n + i;
                tris.push([k, k + 1, k + n + 1]);
                tris.push([k, k + n + 1, k + n]);
            }
        }
        let sheet = |z_of: &dyn Fn(u32, u32) -> (f32, f32)| -> Vec<V4> {
            (0..n * n)
                .map(|k| {
                    let (i, j) = (k % n, k / n);
                    let (y, z) = z_of(i, j);
                    v(i as f32 * 0.1, y, z)
                })
                .collect()
        };
        let flat = sheet(&|_, j| (j as f32 * 0.1, 0.0));
        assert_eq!(count(&flat, &tris).pairs, 0);
        // Rows past the fold (j > 2) go back up at 60° from the plane.
        let (c, s) = (60f32.to_radians().cos(), 60f32.to_radians().sin());
        let folded = sheet(&|_, j| {
            if j <= 2 { (j as f32 * 0.1, 0.0) } else { (0.2 - (j - 2) as f32 * 0.1 * c, (j - 2) as f32 * 0.1 * s) }
        });
        assert_eq!(count(&folded, &tris).pairs, 0);
        // Rows 4 and 5 moved to stand as a vertical strip in the plane y = 0.15, through the
        // triangles between rows 1 and 2 (x offset by 0.03: no point on a sheet's edge).
        let mut crossed = flat.clone();
        for i in 0..n {
            crossed[(4 * n + i) as usize] = v(i as f32 * 0.1 + 0.03, 0.15, 0.05);
            crossed[(5 * n + i) as usize] = v(i as f32 * 0.1 + 0.03, 0.15, -0.05);
        }
        // Each of the strip's vertical edges inside the sheet (i = 0 … 4) and each of its
        // diagonals pierces a triangle between rows 1 and 2; the sheet's edges pierce the strip.
        assert!(count(&crossed, &tris).pairs >= 10, "{:?}", count(&crossed, &tris));
    }

    #[test]
    fn nan_positions_count_nothing_and_do_not_panic() {
        let pos = [v(f32::NAN, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)];
        assert_eq!(count(&pos, &[[0, 1, 2]]).pairs, 0);
        assert_eq!(count(&[], &[]).pairs, 0);
    }
}
