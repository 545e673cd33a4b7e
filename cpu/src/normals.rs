//! `tri_normals` — per triangle: the area-weighted face normal `(b - a) × (c - a)`.
//! `vertex_normals` — per particle: the sum of the adjacent face normals, normalised, and
//! the wind force, which stays in the force buffer for the next substep's `forces`.

use glam::Vec3;
use rayon::prelude::*;

use super::simd::{F, Lanewise, Simd, dispatch, groups, leftover};
use super::{Exec, Fetch, Lanes, for_each, for_each2, v3, v4};
use clothlab_core::grid::{Rows, V4};
use clothlab_core::step_params::StepParams;
use pulp::Simd as Isa;

/// Face normals `N` with `|N| = 2 · area(t)`; w holds `|N|`.
pub fn tri_normals(exec: Exec, triangles: &[[u32; 3]], pos: &[V4], face: &mut [V4]) {
    for_each(exec, face, |t, f| {
        let [a, b, c] = triangles[t];
        let (xa, xb, xc) = (v3(pos[a as usize]), v3(pos[b as usize]), v3(pos[c as usize]));
        let nrm = (xb - xa).cross(xc - xa);
        *f = v4(nrm, nrm.length());
    });
}

/// Vertex normals and wind. A face of normal `N` (|N| = 2A) under wind `w` with
/// coefficient `c` feels `c · A · (n̂·w) n̂ = c (N·w) N / (2 |N|)`; each corner takes a third.
pub fn vertex_normals(
    exec: Exec,
    p: &StepParams,
    face_slots: &Rows<i32>,
    face: &[V4],
    normal: &mut [V4],
    force: &mut [V4],
) {
    let w = v3(p.wind);
    let c = p.wind[3] / 6.0;
    for_each2(exec, normal, force, |i, nrm, f| (*nrm, *f) = vnormal_at(face_slots.row(i), |t| face[t], w, c));
}

/// Normal and wind force of a particle whose faces are `slots`, read through `fetch`.
#[inline(always)]
pub(crate) fn vnormal_at(slots: &[i32], fetch: impl Fetch, w: Vec3, c: f32) -> (V4, V4) {
    let mut sum = Vec3::ZERO;
    let mut wind = Vec3::ZERO;
    for &t in slots {
        if t < 0 {
            continue;
        }
        let f4 = fetch.at(t as usize);
        let nf = v3(f4);
        sum += nf;
        // No wind (c = 0 or w = 0) adds exact zeros: skip the division.
        if c != 0.0 && w != Vec3::ZERO && f4[3] > 0.0 {
            wind += nf * (c * nf.dot(w) / f4[3]);
        }
    }
    (v4(sum.normalize_or_zero(), 0.0), v4(wind, 0.0))
}

/// Face normals in structure-of-arrays form for the fast paths: `f[t][c][q]` is
/// component `c` (x, y, z, |N|) of triangle `t` (0 or 1) of quad `q = qj·(n-1) + qi`,
/// i.e. of triangle `2q + t` of [`tri_normals`].
#[derive(Debug, Clone, Default)]
pub struct FaceLanes {
    f: [[Vec<f32>; 4]; 2],
}

impl FaceLanes {
    /// Triangle `t` (numbered as in the topology) as `[x, y, z, |N|]`.
    #[inline(always)]
    pub fn get(&self, t: usize) -> V4 {
        let (q, k) = (t / 2, t % 2);
        [self.f[k][0][q], self.f[k][1][q], self.f[k][2][q], self.f[k][3][q]]
    }
}

/// `(b − a) × (c − a)` and its length, lane-wise, in glam's operation order.
#[inline(always)]
pub(crate) fn cross_len<S: Isa>(a: &[F<S>; 3], b: &[F<S>; 3], c: &[F<S>; 3]) -> [F<S>; 4] {
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let x = u[1] * v[2] - v[1] * u[2];
    let y = u[2] * v[0] - v[2] * u[0];
    let z = u[0] * v[1] - v[0] * u[1];
    [x, y, z, (x * x + y * y + z * z).sqrt()]
}

/// The two face normals of quad `(i, j)` (corners `p00 = (i, j)`, `p10`, `p01`, `p11`),
/// each `[x, y, z, |N|]`: [`tri_normals`]' arithmetic.
#[inline(always)]
pub(crate) fn quad_normals(p00: Vec3, p10: Vec3, p01: Vec3, p11: Vec3) -> [V4; 2] {
    let t0 = (p01 - p00).cross(p11 - p00);
    let t1 = (p11 - p00).cross(p10 - p00);
    [v4(t0, t0.length()), v4(t1, t1.length())]
}

/// One quad row of [`tri_normals_lanes`], at the width `dispatch` picks.
struct TriRow<'a> {
    qj: usize,
    n: usize,
    pos: &'a [Vec<f32>; 4],
    out: [&'a mut [f32]; 8],
}

impl Lanewise for TriRow<'_> {
    type Out = ();
    #[inline(always)]
    fn run<S: Isa>(self, sd: S) {
        let Self { qj, n, pos, mut out } = self;
        let (m, base) = (n - 1, qj * n);
        for qi in groups(0, m, S::F32_LANES) {
            let at = |k: usize| [F::load(sd, &pos[0], k), F::load(sd, &pos[1], k), F::load(sd, &pos[2], k)];
            let (p00, p10, p01, p11) = (at(base + qi), at(base + qi + 1), at(base + n + qi), at(base + n + qi + 1));
            for (c, v) in cross_len(&p00, &p01, &p11).into_iter().chain(cross_len(&p00, &p11, &p10)).enumerate() {
                v.store(out[c], qi);
            }
        }
        let at = |i: usize| Vec3::new(pos[0][i], pos[1][i], pos[2][i]);
        for qi in leftover(0, m, S::F32_LANES) {
            let k = base + qi;
            let t = quad_normals(at(k), at(k + 1), at(k + n), at(k + n + 1));
            for (c, o) in out.iter_mut().enumerate() {
                o[qi] = t[c / 4][c % 4];
            }
        }
    }
}

/// [`tri_normals`] for a regular grid into [`FaceLanes`], in lanes of the widest
/// instruction set this CPU has;
/// `lanes` must hold the positions. Bit-identical to [`tri_normals`].
pub fn tri_normals_lanes(exec: Exec, n: usize, lanes: &Lanes, out: &mut FaceLanes) {
    let m = n - 1;
    for v in out.f.iter_mut().flatten() {
        v.resize(m * m, 0.0);
    }
    let simd = Simd::detect();
    let [[a0, a1, a2, a3], [b0, b1, b2, b3]] = &mut out.f;
    let row = |qj: usize, ((a0, a1), (a2, a3)): Quad4, ((b0, b1), (b2, b3)): Quad4| {
        dispatch(simd, TriRow { qj, n, pos: &lanes.pos, out: [a0, a1, a2, a3, b0, b1, b2, b3] });
    };
    match exec {
        Exec::Serial => a0
            .chunks_mut(m)
            .zip(a1.chunks_mut(m))
            .zip(a2.chunks_mut(m).zip(a3.chunks_mut(m)))
            .zip(b0.chunks_mut(m).zip(b1.chunks_mut(m)).zip(b2.chunks_mut(m).zip(b3.chunks_mut(m))))
            .enumerate()
            .for_each(|(j, (a, b))| row(j, a, b)),
        Exec::Parallel => a0
            .par_chunks_mut(m)
            .zip(a1.par_chunks_mut(m))
            .zip(a2.par_chunks_mut(m).zip(a3.par_chunks_mut(m)))
            .zip(b0.par_chunks_mut(m).zip(b1.par_chunks_mut(m)).zip(b2.par_chunks_mut(m).zip(b3.par_chunks_mut(m))))
            .enumerate()
            .for_each(|(j, (a, b))| row(j, a, b)),
    }
}

type Quad4<'a> = ((&'a mut [f32], &'a mut [f32]), (&'a mut [f32], &'a mut [f32]));

/// The vertex normals and wind forces of one lane group from its six faces (x, y, z,
/// |N| each, in the face slots' order): [`vnormal_at`]'s arithmetic, lane by lane.
#[inline(always)]
pub(crate) fn vnormal_lanes<S: Isa>(sd: S, faces6: &[[F<S>; 4]; 6], w: Vec3, c: f32) -> ([F<S>; 3], [F<S>; 3]) {
    let zero = F::splat(sd, 0.0);
    let (wl, cl) = ([F::splat(sd, w.x), F::splat(sd, w.y), F::splat(sd, w.z)], F::splat(sd, c));
    let windy = c != 0.0 && w != Vec3::ZERO;
    let mut sum = [zero; 3];
    let mut wind = [zero; 3];
    for f4 in faces6 {
        for k in 0..3 {
            sum[k] += f4[k];
        }
        // No wind (c = 0 or w = 0) adds exact zeros: skip the division.
        if !windy {
            continue;
        }
        let dot = f4[0] * wl[0] + f4[1] * wl[1] + f4[2] * wl[2];
        let q = cl * dot / f4[3];
        let live = f4[3].gt(zero);
        for k in 0..3 {
            wind[k] += F::select(live, f4[k] * q, zero);
        }
    }
    let rcp = F::splat(sd, 1.0) / (sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]).sqrt();
    let ok = rcp.lt(F::splat(sd, f32::INFINITY)) & rcp.gt(zero);
    // Written out: `array::map` is not always inlined, and out of line it runs the
    // vector instructions as calls.
    let nrm = [F::select(ok, sum[0] * rcp, zero), F::select(ok, sum[1] * rcp, zero), F::select(ok, sum[2] * rcp, zero)];
    (nrm, wind)
}

/// One row of [`vertex_normals_rows`], at the width `dispatch` picks.
struct VertexRow<'a> {
    j: usize,
    n: usize,
    faces: &'a FaceLanes,
    face_slots: &'a Rows<i32>,
    wind: (Vec3, f32),
    nrow: &'a mut [V4],
    frow: &'a mut [V4],
}

impl Lanewise for VertexRow<'_> {
    type Out = ();
    #[inline(always)]
    fn run<S: Isa>(self, sd: S) {
        let Self { j, n, faces, face_slots, wind: (w, c), nrow, frow } = self;
        let m = n - 1;
        let lanes = S::F32_LANES;
        let interior = j >= 1 && j + 1 < n;
        let (lo, hi) = if interior { (1, n - 1) } else { (0, 0) };
        for i0 in groups(lo, hi, lanes) {
            // Quads (i-1, j-1), (i, j-1), (i-1, j), (i, j) for i = i0 .. i0 + lanes.
            let (qa, qb, qc, qd) = ((j - 1) * m + i0 - 1, (j - 1) * m + i0, j * m + i0 - 1, j * m + i0);
            let f = &faces.f;
            let at = |t: usize, q: usize| {
                [F::load(sd, &f[t][0], q), F::load(sd, &f[t][1], q), F::load(sd, &f[t][2], q), F::load(sd, &f[t][3], q)]
            };
            let faces6 = [at(0, qa), at(1, qa), at(0, qb), at(1, qc), at(0, qd), at(1, qd)];
            let (nv, wv) = vnormal_lanes(sd, &faces6, w, c);
            for k in 0..lanes {
                nrow[i0 + k] = [nv[0].lane(k), nv[1].lane(k), nv[2].lane(k), 0.0];
                frow[i0 + k] = [wv[0].lane(k), wv[1].lane(k), wv[2].lane(k), 0.0];
            }
        }
        let edges = if interior { vec![0, n - 1] } else { (0..n).collect() };
        for i in leftover(lo, hi, lanes).chain(edges) {
            (nrow[i], frow[i]) = vnormal_at(face_slots.row(j * n + i), |t| faces.get(t), w, c);
        }
    }
}

/// [`vertex_normals`] row by row from [`FaceLanes`], the interior of each row in lanes
/// of the widest instruction set this CPU has. Bit-identical to [`vertex_normals`].
pub fn vertex_normals_rows(
    exec: Exec,
    p: &StepParams,
    face_slots: &Rows<i32>,
    faces: &FaceLanes,
    normal: &mut [V4],
    force: &mut [V4],
) {
    let n = p.n as usize;
    let simd = Simd::detect();
    let wind = (v3(p.wind), p.wind[3] / 6.0);
    let row = |j: usize, nrow: &mut [V4], frow: &mut [V4]| {
        dispatch(simd, VertexRow { j, n, faces, face_slots, wind, nrow, frow });
    };
    match exec {
        Exec::Serial => normal.chunks_mut(n).zip(force.chunks_mut(n)).enumerate().for_each(|(j, (a, b))| row(j, a, b)),
        Exec::Parallel => {
            normal.par_chunks_mut(n).zip(force.par_chunks_mut(n)).enumerate().for_each(|(j, (a, b))| row(j, a, b))
        }
    }
}
