//! What the contact between triangles computes of one pair (docs/contact.md): its
//! closest points' sides, its response in a pass (the velocity pass's impulse with
//! Coulomb friction, the separation's push), its fixed-point shares, a vertex's cut to its
//! bound, VBD's contact terms. The kernels' twins (`crate::tri_contact`) call these, and
//! through them the CPU solvers (`crate::tri_pipeline::Contact`).

use glam::Vec3;

use clothlab_core::tri_contact::*;
/// One pair's response: `change` to the relative motion of its closest points (p − q),
/// `m` = Σ inverse mass × weight² over its vertices (how much a unit impulse moves it).
pub(crate) struct Response {
    pub(crate) s: Sides,
    pub(crate) m: f32,
    pub(crate) change: Vec3,
}

impl Response {
    /// The vertices it moves (weight ≠ 0): side a's, then side b's.
    pub(crate) fn acting(&self) -> impl Iterator<Item = u32> + '_ {
        self.sides().map(|(k, _, _)| k)
    }

    /// Each vertex it moves with its weight and its side's sign (+1 for a, −1 for b).
    fn sides(&self) -> impl Iterator<Item = (u32, f32, f32)> + '_ {
        [(&self.s.a, &self.s.wa, 1.0f32), (&self.s.b, &self.s.wb, -1.0)]
            .into_iter()
            .flat_map(|(ks, ws, sign)| ks.iter().zip(ws).filter(|(_, w)| **w != 0.0).map(move |(&k, &w)| (k, w, sign)))
    }

    /// Each vertex's share of it in fixed point of `unit`: `± inv · w · change / m` (the
    /// impulse that makes the pair's change, spread so that the pair's momentum does not
    /// change), scaled by one over `most` (the most pairs any of its vertices is in: the
    /// same factor on both sides, so the momentum is still kept, and a vertex in k pairs
    /// is not moved k times over — a Jacobi sum's overshoot), truncated to i32 (a
    /// saturating conversion: what a GPU's i32 atomics then add with wrap-around). The
    /// one computation of a share (the `tri_*_share` kernels' twins).
    pub(crate) fn shares(
        &self,
        most: u32,
        inv: impl Fn(u32) -> f32,
        unit: f32,
    ) -> impl Iterator<Item = (u32, [i32; 3])> {
        let scale = (1.0 / most.max(1) as f32) * (1.0 / self.m) * (1.0 / unit);
        self.sides().map(move |(k, w, sign)| {
            let d = self.change * (sign * inv(k) * w * scale);
            (k, [d[0] as i32, d[1] as i32, d[2] as i32])
        })
    }
}

/// A fixed-point sum of shares ([`Response::shares`]) in `unit`s, as a float.
pub(crate) fn from_units(sum: i32, unit: f32) -> f32 {
    sum as f32 * unit
}

/// Vertex `x`'s motion since `x0` cut to `bound` where it is longer (and finite), the cut
/// taken from its velocity `v` over `dt`; whether it was cut. (The `tri_clamp`
/// kernel's twin.)
pub(crate) fn clamp_to_bound(
    x: &mut clothlab_core::grid::V4,
    v: &mut clothlab_core::grid::V4,
    x0: Vec3,
    bound: f32,
    dt: f32,
) -> bool {
    let d = Vec3::from_slice(&x[..3]) - x0;
    let len = d.length();
    if len <= bound || !len.is_finite() {
        return false;
    }
    let to = x0 + d * (bound * (1.0 / len));
    for c in 0..3 {
        v[c] += (to[c] - x[c]) * (1.0 / dt);
        x[c] = to[c];
    }
    true
}

/// What a pass computes of a pair: the velocity pass's impulse, or the separation's push.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pass {
    /// At the substep's start (Bridson, Fedkiw & Anderson 2002's inelastic impulses,
    /// before the step): every pair whose relative normal velocity at its closest points
    /// would bring it under the thickness within the substep gets the impulse that
    /// brings it to the thickness instead, spread over its vertices by their weights and
    /// inverse masses so that the pair's momentum does not change, and Coulomb friction
    /// on its sliding. It keeps the motion bounds from cutting most approaches: a cut is
    /// not an internal force, an impulse is.
    Velocity,
    /// After the integrator, a Jacobi pass: each pair closer than the thickness pushed
    /// apart to it along the line between its closest points (the constraint
    /// `n·(p − q) ≥ thickness` projected with the vertices' inverse masses and the
    /// closest points' weights: the pair's momentum kept).
    Separation,
}

/// A pair's response in `pass` (the one computation of it: the GPU kernels' twins call
/// it), `None` where it has none: with the inverse masses
/// `inv`, the velocities `vel` (the velocity pass's only), the `thickness` (none where it
/// is not positive: a scene without the contact), the substep `dt` and Coulomb's `mu`.
///
/// - Separation: a pair closer than the thickness is pushed apart to it along the line
///   between its closest points (`n (t − d)`).
/// - Velocity: a pair whose relative normal velocity would bring it under the thickness
///   within `dt` has it changed to what brings it to the thickness instead, and its
///   sliding stopped where μs times that change can, else slowed by μk times it.
pub(crate) fn response(
    s: Sides,
    inv: impl Fn(u32) -> f32,
    vel: &[clothlab_core::grid::V4],
    thickness: f32,
    dt: f32,
    mu: Friction,
    pass: Pass,
) -> Option<Response> {
    if thickness.is_nan() || thickness <= 0.0 {
        return None;
    }
    let (d, n) = s.gap();
    let m = mass_term(&s.a, &s.wa, &inv) + mass_term(&s.b, &s.wb, &inv);
    if pass == Pass::Separation {
        return (m > 0.0 && n.is_finite() && d < thickness).then(|| Response { s, m, change: n * (thickness - d) });
    }
    if m == 0.0 || !n.is_finite() {
        return None;
    }
    let speed = |ks: &[u32; 3], ws: &[f32; 3]| -> Vec3 {
        ks.iter().zip(ws).map(|(&k, &w)| Vec3::from_slice(&vel[k as usize][..3]) * w).sum()
    };
    let rel = speed(&s.a, &s.wa) - speed(&s.b, &s.wb);
    let vn = rel.dot(n);
    // The normal speed that closes the gap to the thickness by the substep's end.
    let want = (thickness - d) * (1.0 / dt);
    if vn >= want {
        return None;
    }
    let dn = want - vn;
    // Friction on the sliding, from the normal change (a change of the relative velocity
    // per unit of `m` is an impulse).
    let slide = rel - n * vn;
    let sl = slide.length();
    let stop = if sl == 0.0 || mu == Friction::default() {
        Vec3::ZERO
    } else if sl <= mu.stat * dn {
        -slide
    } else {
        -slide * (mu.kinetic * dn * (1.0 / sl)).min(1.0)
    };
    Some(Response { s, m, change: n * dn + stop })
}

/// Σ inverse mass × weight² of a side.
pub(crate) fn mass_term(ks: &[u32; 3], ws: &[f32; 3], inv: impl Fn(u32) -> f32) -> f32 {
    ks.iter().zip(ws).map(|(&k, &w)| inv(k) * w * w).sum()
}

/// Coulomb's coefficients at the contacts between triangles (both 0: frictionless).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Friction {
    /// μs: a contact whose sliding the normal impulse times μs can stop sticks.
    pub stat: f32,
    /// μk: else the sliding loses μk times the normal impulse.
    pub kinetic: f32,
}

/// A pair's vertices, their weights at the closest points and the points: `(a, wa, p)`
/// on one side, `(b, wb, q)` on the other, and a normal for when p and q coincide (a side
/// of fewer than three vertices has weight 0 on the rest).
pub(crate) struct Sides {
    pub(crate) a: [u32; 3],
    pub(crate) wa: [f32; 3],
    pub(crate) p: Vec3,
    pub(crate) b: [u32; 3],
    pub(crate) wb: [f32; 3],
    pub(crate) q: Vec3,
    pub(crate) fallback: Vec3,
}

impl Sides {
    /// The distance between the closest points and the unit normal from q to p (the
    /// fallback where they coincide), as [`response`] and [`vbd_terms`] take them; the
    /// normal may be NaN (degenerate primitives), which each caller refuses.
    pub(crate) fn gap(&self) -> (f32, Vec3) {
        let d = (self.p - self.q).length();
        (d, if d > 0.0 { (self.p - self.q) * (1.0 / d) } else { self.fallback })
    }

    /// Vertex `v` and triangle `tri` at `pos`.
    pub(crate) fn vertex_triangle(pos: &[clothlab_core::grid::V4], v: u32, tri: [u32; 3]) -> Self {
        let at = |k: u32| Vec3::from_slice(&pos[k as usize][..3]);
        let (x, a, b, c) = (at(v), at(tri[0]), at(tri[1]), at(tri[2]));
        let r = point_triangle(x, a, b, c);
        let fallback = (b - a).cross(c - a).normalize();
        Sides { a: [v, v, v], wa: [1.0, 0.0, 0.0], p: x, b: tri, wb: r.weights, q: r.point, fallback }
    }

    /// Edges `[a, b]` and `[c, d]` at `pos`.
    pub(crate) fn edge_edge(pos: &[clothlab_core::grid::V4], [a, b]: [u32; 2], [c, d]: [u32; 2]) -> Self {
        let at = |k: u32| Vec3::from_slice(&pos[k as usize][..3]);
        let r = edge_edge(at(a), at(b), at(c), at(d));
        let fallback = (at(b) - at(a)).cross(at(d) - at(c)).normalize();
        Sides {
            a: [a, b, b],
            wa: [1.0 - r.s, r.s, 0.0],
            p: r.p,
            b: [c, d, d],
            wb: [1.0 - r.t, r.t, 0.0],
            q: r.q,
            fallback,
        }
    }
}

/// Whether VBD's contact terms act on vertex `k` while colour `colour` is swept: a
/// vertex of that colour (`colour_of`: each particle's) that is not held (pinned, its
/// `pos` w 0, or the grabbed `grab`). [`Contact::vbd_terms`] and
/// `cpu::tri_contact::tri_vbd` (the `tri_vbd` kernel's twin) both ask this.
pub(crate) fn vbd_wanted<'a>(
    pos: &'a [clothlab_core::grid::V4],
    colour_of: &'a [u32],
    colour: u32,
    grab: i32,
) -> impl Fn(u32) -> bool + Copy + 'a {
    move |k: u32| colour_of[k as usize] == colour && k as i32 != grab && pos[k as usize][3] != 0.0
}

/// A pair's contact energy inside VBD's local solves (the paper's §3.5 for the contact
/// between primitives): `E = ½ k (t − d)²` while the closest points are `d` < `thickness`
/// (`t`) apart, `n` the normal from the second side's point to the first's. Each acting
/// vertex (weight `w` ≠ 0) that `wanted` takes (the colour being swept, not held) gets
/// its force `−∂E/∂x = ± k (t − d) w n` (`+` on the first side) in units of
/// `t / CONTACT_UNITS`, and its block `k w n nᵀ` in units of `1 / CONTACT_UNITS`, over
/// `k` (the block multiplies it in: `cpu::vbd`), handed to `add` word by word (its index
/// among the sums, [`VBD_TERMS`] words a particle, and the value: a 32-bit integer,
/// truncated, added with wrap-around — the same sum in any order, as the GPU's atomics).
/// Returns whether the pair is closer than `t`.
///
/// The block is the Gauss–Newton `k w² n nᵀ` raised to `k w n nᵀ` (w ≤ 1: still the
/// pair's energy's majorant along n), so that a vertex's step is its pairs' gaps to the
/// thickness averaged by weight and never more than the largest. With `w²` a vertex whose
/// pairs mix weights (vertex–triangle at 1, edge–edge at ½) stepped past the thickness,
/// where the one-sided energy is zero and the inertia pulled it back: a sheet pressed to
/// 0.6 t on another went to 1.03 t and back to 0.6 t sweep after sweep.
pub(crate) fn vbd_terms(
    s: &Sides,
    thickness: f32,
    wanted: impl Fn(u32) -> bool,
    mut add: impl FnMut(usize, u32),
) -> bool {
    if thickness.is_nan() || thickness <= 0.0 {
        return false;
    }
    let (d, n) = s.gap();
    // (A NaN distance adds nothing either.)
    if d.is_nan() || d >= thickness || !n.is_finite() {
        return false;
    }
    let scale = (thickness - d) * (1.0 / (thickness * (1.0 / clothlab_core::tables::CONTACT_UNITS)));
    for (ks, ws, sign) in [(&s.a, &s.wa, 1.0f32), (&s.b, &s.wb, -1.0)] {
        for (&k, &w) in ks.iter().zip(ws) {
            if w == 0.0 || !wanted(k) {
                continue;
            }
            let f = n * (sign * w * scale);
            // The block's k w n nᵀ, not the Gauss–Newton k w² n nᵀ (see above).
            let hw = w * clothlab_core::tables::CONTACT_UNITS;
            let h = [n.x * n.x * hw, n.y * n.y * hw, n.z * n.z * hw, n.x * n.y * hw, n.x * n.z * hw, n.y * n.z * hw];
            for (j, v) in f.to_array().into_iter().chain(h).enumerate() {
                // Saturating conversion and wrapping sums: what a GPU's i32 atomics do.
                add(VBD_TERMS * k as usize + j, v as i32 as u32);
            }
        }
    }
    true
}
