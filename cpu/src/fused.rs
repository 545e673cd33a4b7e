//! The Verlet substep of the CPU solvers in one sweep over the grid.
//!
//! Kernel by kernel, a substep passes over the whole state six times or more (forces and
//! springs, integrate and collide, each strain-limit pass, the two normal kernels, and a
//! transpose before each SIMD kernel); at n ≥ 512 the state no longer fits in the caches
//! and every pass goes to memory. Here each row goes through every kernel while its
//! neighbours are still in cache: a wavefront over the rows, in which at row `j`
//!
//! | stage | row | reads |
//! |---|---|---|
//! | `forces` + `springs` + `integrate` + `collide` (A) | `j` | old rows `j−2 ..= j+2` |
//! | `strain_count` before pass `k` (1 ..= l) | `j − 2k + 1` | pass `k−1`'s rows `j−2k ..= j−2k+2` |
//! | strain-limit pass `k` | `j − 2k` | pass `k−1`'s and count `k`'s rows `j−2k−1 ..= j−2k+1` |
//! | `tri_normals` | quad row `j − L − 1` | final rows `j−L−1`, `j−L` |
//! | `vertex_normals` | `j − L − 1` | quad rows `j−L−2`, `j−L−1` |
//!
//! (`L = 2l`: a pass divides each spring by the larger of its ends' counts, so it needs
//! the counts of the rows beside its own, one row behind them.)
//!
//! Each stage keeps its last four rows in a ring, so what a substep moves to and from
//! memory is the old state once and the new state once. The kernels are the same
//! functions as the twins' (lanes the fast path cannot take — pinned, grabbed, in a
//! collider or the floor — and grids narrower than a vector run the scalar twins
//! themselves; lane groups at the edge columns mask out the neighbours beyond the edge),
//! so the result is the twins' bit for bit; the tests check it at every vector width.
//!
//! In parallel the rows are cut into bands, one task each; a band recomputes the `L + 1`
//! rows of stage A (and `1 + 2(l − k)` of strain pass `k`, one more of its counts) beyond
//! each of its edges that its neighbour owns, instead of waiting for them, and writes only
//! its own rows. The new
//! state goes to other buffers (the old one is read by the bands' edges throughout).

use glam::Vec3;
use rayon::prelude::*;

use super::collide::collide_at;
use super::forces::{forces_at, forces_consts};
use super::integrate::integrate_at;
use super::normals::{cross_len, quad_normals, vnormal_at, vnormal_lanes};
use super::simd::{F, Lanewise, M, Simd, dispatch, groups, leftover};
use super::springs::{GridSlots, gather_at};
use super::strain_limit::{count_at, limit_at, moved_vel};
use super::{Exec, Fetch, v3};
use clothlab_core::contact::{Bound, Shape};
use clothlab_core::grid::{ClothState, SLOT_OFFSETS, SLOTS, STRAIN_SLOTS, SpringSlot, TETHER_SLOTS, Tether, V4};
use clothlab_core::layout::STRAIN_AIM;
use clothlab_core::step_params::StepParams;

use pulp::Simd as Isa;

/// Columns of zeros on each side of a ring's rows: a lane group at a grid's edge reads
/// its missing neighbours there (and masks them out, [`in_grid`]) instead of going
/// through the scalar twins (which cost 8 % of the sweep at n = 512 for 4 columns).
const PAD: usize = 16;

/// Rows of a few component arrays; row `r` lives in slot `r % rows` (`rows` a power of
/// two), so a stage keeps the rows the next one still reads. Each row has [`PAD`]
/// columns on either side that are never written.
#[derive(Debug, Default)]
struct Ring {
    data: Vec<f32>,
    comps: usize,
    width: usize,
    rows: usize,
}

impl Ring {
    fn reset(&mut self, comps: usize, width: usize, rows: usize) {
        let shape = (comps, width + 2 * PAD, rows);
        if shape != (self.comps, self.width, self.rows) {
            (self.comps, self.width, self.rows) = shape;
            self.data.clear();
            self.data.resize(rows * comps * self.width, 0.0);
        }
    }

    /// Where column 0 of component `c` of `row` is.
    #[inline(always)]
    fn at(&self, row: usize, c: usize) -> usize {
        ((row & (self.rows - 1)) * self.comps + c) * self.width + PAD
    }

    /// Lanes of component `c` of `row` from column `col`, which may lie up to [`PAD`]
    /// columns outside the grid (zeros there).
    #[inline(always)]
    fn lanes_at<S: Isa>(&self, sd: S, row: usize, c: usize, col: isize) -> F<S> {
        F::load(sd, &self.data, self.at(row, c).wrapping_add_signed(col))
    }

    #[inline(always)]
    fn lanes3_at<S: Isa>(&self, sd: S, row: usize, c0: usize, col: isize) -> [F<S>; 3] {
        [self.lanes_at(sd, row, c0, col), self.lanes_at(sd, row, c0 + 1, col), self.lanes_at(sd, row, c0 + 2, col)]
    }

    /// Writes lanes `x` (x, y, z) and `w` to components 0 ..= 3 of `row` from `i`.
    #[inline(always)]
    fn store4<S: Isa>(&mut self, row: usize, i: usize, x: &[F<S>; 3], w: F<S>) {
        for (c, v) in x.iter().chain([&w]).enumerate() {
            self.store(row, c, i, *v);
        }
    }

    #[inline(always)]
    fn lanes<S: Isa>(&self, sd: S, row: usize, c: usize, i: usize) -> F<S> {
        F::load(sd, &self.data, self.at(row, c) + i)
    }

    #[inline(always)]
    fn lanes3<S: Isa>(&self, sd: S, row: usize, c0: usize, i: usize) -> [F<S>; 3] {
        [self.lanes(sd, row, c0, i), self.lanes(sd, row, c0 + 1, i), self.lanes(sd, row, c0 + 2, i)]
    }

    #[inline(always)]
    fn get(&self, row: usize, c: usize, i: usize) -> f32 {
        self.data[self.at(row, c) + i]
    }

    #[inline(always)]
    fn get4(&self, row: usize, c0: usize, i: usize) -> V4 {
        std::array::from_fn(|c| self.get(row, c0 + c, i))
    }

    #[inline(always)]
    fn set(&mut self, row: usize, c: usize, i: usize, v: f32) {
        let a = self.at(row, c) + i;
        self.data[a] = v;
    }

    #[inline(always)]
    fn put4(&mut self, row: usize, c0: usize, i: usize, v: V4) {
        for (c, x) in v.into_iter().enumerate() {
            self.set(row, c0 + c, i, x);
        }
    }

    #[inline(always)]
    fn store<S: Isa>(&mut self, row: usize, c: usize, i: usize, v: F<S>) {
        let a = self.at(row, c) + i;
        v.store(&mut self.data, a);
    }
}

/// One band's rings, kept between substeps.
#[derive(Debug, Default)]
pub(crate) struct Band {
    /// The old positions, velocities and force (x, y, z, w, vx, vy, vz, fx, fy, fz),
    /// eight rows.
    input: Ring,
    /// Stage A's positions and velocities (x, y, z, w, vx, vy, vz), then each strain
    /// pass's.
    stages: Vec<Ring>,
    /// Each strain pass's counts of over-stretched springs (one component).
    counts: Vec<Ring>,
    /// The face normals of a quad row: triangle 0's x, y, z, |N|, then triangle 1's.
    faces: Ring,
}

/// The tethers as component arrays, per slot: the pins and the rest lengths.
#[derive(Debug, Default, Clone)]
pub(crate) struct TetherLanes {
    pin: [Vec<i32>; TETHER_SLOTS],
    rest: [Vec<f32>; TETHER_SLOTS],
}

impl TetherLanes {
    pub(crate) fn new(tethers: &[[Tether; TETHER_SLOTS]]) -> Self {
        Self {
            pin: std::array::from_fn(|t| tethers.iter().map(|x| x[t].pin).collect()),
            rest: std::array::from_fn(|t| tethers.iter().map(|x| x[t].rest).collect()),
        }
    }
}

/// Components of [`Soa`]: x, y, z, w of the positions, then x, y, z of the velocity, the
/// force and the normal.
const POS: usize = 0;
const VEL: usize = 4;
const FORCE: usize = 7;
const NORMAL: usize = 10;
const COMPS: usize = 13;

/// The state as component arrays, the fused sweep's layout: a vector of eight or
/// sixteen particles is then one load, where `[x, y, z, w]` particles would need a
/// transpose at every read and write (measured: a third of the sweep's time at n = 512).
/// `ClothState` is converted to it before the first fused substep and back after the
/// last one of a frame.
#[derive(Debug, Default, Clone)]
pub(crate) struct Soa {
    c: [Vec<f32>; COMPS],
}

impl Soa {
    /// Takes `st`.
    pub(crate) fn load(&mut self, exec: Exec, st: &ClothState) {
        let np = st.pos.len();
        for v in &mut self.c {
            v.resize(np, 0.0);
        }
        let comp = |k: usize, v: &mut Vec<f32>| {
            let (src, c) = match k {
                0..4 => (&st.pos, k),
                4..7 => (&st.vel, k - 4),
                7..10 => (&st.force, k - 7),
                _ => (&st.normal, k - 10),
            };
            for (o, p) in v.iter_mut().zip(src) {
                *o = p[c];
            }
        };
        match exec {
            Exec::Serial => self.c.iter_mut().enumerate().for_each(|(k, v)| comp(k, v)),
            Exec::Parallel => self.c.par_iter_mut().enumerate().for_each(|(k, v)| comp(k, v)),
        }
    }

    /// Writes the state to `st` (w of `vel`, force and normal 0, as every kernel leaves
    /// it).
    pub(crate) fn store(&self, exec: Exec, st: &mut ClothState) {
        const CHUNK: usize = 4096;
        let c = &self.c;
        // Zipped slices, so that the loops have no bounds checks and vectorise.
        let put = |dst: &mut [V4], x: &[f32], y: &[f32], z: &[f32], w: Option<&[f32]>| match w {
            Some(w) => {
                for ((((o, x), y), z), w) in dst.iter_mut().zip(x).zip(y).zip(z).zip(w) {
                    *o = [*x, *y, *z, *w];
                }
            }
            None => {
                for (((o, x), y), z) in dst.iter_mut().zip(x).zip(y).zip(z) {
                    *o = [*x, *y, *z, 0.0];
                }
            }
        };
        let bufs = [
            (&mut st.pos, POS, true),
            (&mut st.vel, VEL, false),
            (&mut st.force, FORCE, false),
            (&mut st.normal, NORMAL, false),
        ];
        for (dst, c0, has_w) in bufs {
            let part = |(k, dst): (usize, &mut [V4])| {
                let r = k * CHUNK..k * CHUNK + dst.len();
                let w = has_w.then(|| &c[c0 + 3][r.clone()]);
                put(dst, &c[c0][r.clone()], &c[c0 + 1][r.clone()], &c[c0 + 2][r], w)
            };
            match exec {
                Exec::Serial => dst.chunks_mut(CHUNK).enumerate().for_each(part),
                Exec::Parallel => dst.par_chunks_mut(CHUNK).enumerate().for_each(part),
            }
        }
    }

    /// Puts the moving pins of `slots` at their poses (`poses`: one substep's block), as
    /// [`clothlab_core::pins::drive`] does on `ClothState`.
    pub(crate) fn drive(&mut self, slots: &[clothlab_core::pins::PinSlot], poses: &[clothlab_core::pins::PinPose]) {
        for (i, x, v) in clothlab_core::pins::placed(slots, poses, 0) {
            for k in 0..3 {
                self.c[POS + k][i] = x[k];
                self.c[VEL + k][i] = v[k];
            }
        }
    }

    /// Room for `np` particles.
    pub(crate) fn resize(&mut self, np: usize) {
        for v in &mut self.c {
            v.resize(np, 0.0);
        }
    }
}

/// What a substep reads: the old state, the topology and the step's constants.
pub(crate) struct Step<'a> {
    pub p: &'a StepParams,
    pub iters: usize,
    /// The regular grid's slots (`ClothTopology::grid_slots`): the sweep reads no table.
    pub uni: &'a [SpringSlot; SLOTS],
    pub tethers: &'a [[Tether; TETHER_SLOTS]],
    pub tether_lanes: &'a TetherLanes,
    pub face_slots: &'a clothlab_core::grid::Rows<i32>,
    pub colliders: super::collide::Colliders<'a>,
    pub old: &'a Soa,
}

impl Step<'_> {
    #[inline(always)]
    fn pos(&self, k: usize) -> V4 {
        let c = &self.old.c;
        [c[0][k], c[1][k], c[2][k], c[3][k]]
    }

    #[inline(always)]
    fn vel(&self, k: usize) -> V4 {
        let c = &self.old.c;
        [c[4][k], c[5][k], c[6][k], 0.0]
    }

    #[inline(always)]
    fn force(&self, k: usize) -> V4 {
        let c = &self.old.c;
        [c[7][k], c[8][k], c[9][k], 0.0]
    }
}

/// A band's rows of the new state, component by component (as [`Soa`]).
struct Next<'a> {
    c: [&'a mut [f32]; COMPS],
}

impl Next<'_> {
    /// Sets components `c0 .. c0 + len` of particle `i` from `v`.
    #[inline(always)]
    fn put(&mut self, c0: usize, len: usize, i: usize, v: V4) {
        for (c, x) in v.into_iter().enumerate().take(len) {
            self.c[c0 + c][i] = x;
        }
    }

    /// Stores vectors `v` as components `c0 ..` from particle `i`.
    #[inline(always)]
    fn store<S: Isa>(&mut self, c0: usize, i: usize, v: &[F<S>]) {
        for (c, x) in v.iter().enumerate() {
            x.store(self.c[c0 + c], i);
        }
    }
}

/// One Verlet substep (forces, springs, integrate, collide, `iters` strain passes,
/// normals) from `s` into `next`, at `simd`'s width.
pub(crate) fn substep(exec: Exec, simd: Simd, s: &Step<'_>, bands: &mut Vec<Band>, next: &mut Soa) {
    let n = s.p.n as usize;
    let rows = match exec {
        Exec::Serial => n,
        // Two bands per thread, so that a thread slowed down (the VM's other load) holds
        // up at most half a thread's work; no band under 32 rows, whose edges would cost
        // more than a tenth of it again.
        Exec::Parallel => n.div_ceil(2 * rayon::current_num_threads()).max(32),
    };
    let count = n.div_ceil(rows);
    bands.resize_with(count, Band::default);
    let mut chunks = next.c.each_mut().map(|v| v.chunks_mut(rows * n));
    let outs: Vec<Next<'_>> =
        (0..count).map(|_| Next { c: chunks.each_mut().map(|it| it.next().expect("a chunk per band")) }).collect();
    let run = |(b, (band, out)): (usize, (&mut Band, Next<'_>))| {
        let r0 = b * rows;
        let r1 = (r0 + rows).min(n);
        dispatch(simd, BandJob { s, band, r0, r1, out });
    };
    match exec {
        Exec::Serial => bands.iter_mut().zip(outs).enumerate().for_each(run),
        Exec::Parallel => bands.par_iter_mut().zip(outs).enumerate().for_each(run),
    }
}

/// One band's rows `r0 .. r1`.
struct BandJob<'a, 'b> {
    s: &'a Step<'a>,
    band: &'b mut Band,
    r0: usize,
    r1: usize,
    out: Next<'b>,
}

impl Lanewise for BandJob<'_, '_> {
    type Out = ();
    #[inline(always)]
    fn run<S: Isa>(self, sd: S) {
        run_band(sd, self.s, self.band, self.r0, self.r1, self.out)
    }
}

/// The wavefront over rows `r0 .. r1` (see the module notes).
#[inline(always)]
fn run_band<S: Isa>(sd: S, s: &Step<'_>, band: &mut Band, r0: usize, r1: usize, mut out: Next<'_>) {
    let n = s.p.n as usize;
    let l = s.iters;
    // The rows between stage A and the final positions: two per pass (its counts, then it).
    let lag = 2 * l;
    band.input.reset(10, n, 8);
    band.stages.resize_with(l + 1, Ring::default);
    for r in &mut band.stages {
        r.reset(7, n, 4);
    }
    band.counts.resize_with(l, Ring::default);
    for r in &mut band.counts {
        r.reset(1, n, 4);
    }
    band.faces.reset(8, n - 1, 4);
    // Stage k (0: A, k: strain pass k) computes rows lo(k) .. hi(k), pass k's counts one
    // more on each side (lo(k) − 1 .. hi(k) + 1); quad rows r0 − 1 .. r1 are needed for the
    // normals of r0 .. r1.
    let lo = |k: usize| r0.saturating_sub(1 + 2 * (l - k));
    let hi = |k: usize| (r1 + 1 + 2 * (l - k)).min(n);
    let (q_lo, q_hi) = (r0.saturating_sub(1), r1.min(n - 1));
    let mut loaded = lo(0).saturating_sub(2);
    for j in lo(0)..=r1 + lag {
        if j < hi(0) {
            while loaded < (j + 3).min(n) {
                load_row(sd, s, &mut band.input, loaded);
                loaded += 1;
            }
            let own = (r0..r1).contains(&j).then(|| ((j - r0) * n, l == 0));
            stage_a(sd, s, &band.input, &mut band.stages[0], j, own, &mut out);
        }
        for k in 1..=l {
            // Pass k's counts of row j − 2k + 1, from pass k − 1's rows around it.
            if let Some(rc) = (j + 1).checked_sub(2 * k)
                && rc + 1 >= lo(k)
                && rc < (hi(k) + 1).min(n)
            {
                stage_count(sd, s, &band.stages[k - 1], &mut band.counts[k - 1], rc);
            }
            let Some(r) = j.checked_sub(2 * k) else { continue };
            if r < lo(k) || r >= hi(k) {
                continue;
            }
            let (done, rest) = band.stages.split_at_mut(k);
            let own = ((r0..r1).contains(&r) && k == l).then(|| (r - r0) * n);
            stage_strain(sd, s, &done[k - 1], &band.counts[k - 1], &mut rest[0], r, own, &mut out);
        }
        let Some(q) = j.checked_sub(lag + 1) else { continue };
        if (q_lo..q_hi).contains(&q) {
            stage_tri(sd, n, &band.stages[l], &mut band.faces, q);
        }
        if (r0..r1).contains(&q) {
            stage_vert(sd, s, &band.faces, q, (q - r0) * n, &mut out);
        }
    }
}

/// Old row `j` into the input ring: positions, velocities and force.
#[inline(always)]
fn load_row<S: Isa>(sd: S, s: &Step<'_>, input: &mut Ring, j: usize) {
    let n = s.p.n as usize;
    let c = &s.old.c;
    for i in groups(0, n, S::F32_LANES) {
        let k = j * n + i;
        let at = |c: &[f32]| F::load(sd, c, k);
        for q in 0..4 {
            input.store(j, q, i, at(&c[POS + q]));
        }
        for q in 0..3 {
            input.store(j, 4 + q, i, at(&c[VEL + q]));
            input.store(j, 7 + q, i, at(&c[FORCE + q]));
        }
    }
    for i in leftover(0, n, S::F32_LANES) {
        let k = j * n + i;
        let (a, b, f) = (s.pos(k), s.vel(k), s.force(k));
        input.put4(j, 0, i, a);
        for q in 0..3 {
            input.set(j, 4 + q, i, b[q]);
            input.set(j, 7 + q, i, f[q]);
        }
    }
}

/// The old positions and velocities, by particle.
struct OldPos<'a>(&'a Step<'a>);
struct OldVel<'a>(&'a Step<'a>);

impl Fetch for OldPos<'_> {
    #[inline(always)]
    fn at(&self, k: usize) -> V4 {
        self.0.pos(k)
    }
}

impl Fetch for OldVel<'_> {
    #[inline(always)]
    fn at(&self, k: usize) -> V4 {
        self.0.vel(k)
    }
}

/// The previous stage's positions around row `j` (neighbours are within a row; a
/// tether's pin anywhere is fixed: [`pin_at`]).
struct RingFetch<'a> {
    s: &'a Step<'a>,
    src: &'a Ring,
    j: usize,
}

impl Fetch for RingFetch<'_> {
    #[inline(always)]
    fn at(&self, k: usize) -> V4 {
        let n = self.s.p.n as usize;
        let r = k / n;
        if r + 1 >= self.j && r <= self.j + 1 { self.src.get4(r, 0, k % n) } else { pin_at(self.s, k) }
    }
}

/// Face normals by triangle, from the ring of quad rows.
#[derive(Clone, Copy)]
struct FaceFetch<'a> {
    faces: &'a Ring,
    m: usize,
}

impl Fetch for FaceFetch<'_> {
    #[inline(always)]
    fn at(&self, t: usize) -> V4 {
        let (q, k) = (t / 2, t % 2);
        self.faces.get4(q / self.m, 4 * k, q % self.m)
    }
}

/// Stage A's scalar path for particle `k`: the twins themselves.
#[inline(always)]
fn a_scalar(s: &Step<'_>, k: usize) -> (V4, V4) {
    let (g, drag) = forces_consts(s.p);
    let f = forces_at(s.force(k), s.vel(k), g, drag);
    let grid = GridSlots { n: s.p.n as usize, uni: s.uni };
    finish_at(s, k, gather_at(k, &grid, OldPos(s), OldVel(s), f))
}

/// The twins' `integrate` then `collide` for particle `k` under force `f`.
#[inline(always)]
fn finish_at(s: &Step<'_>, k: usize, f: V4) -> (V4, V4) {
    let (mut x4, mut v4) = (s.pos(k), s.vel(k));
    integrate_at(k, s.p, f, &mut x4, &mut v4);
    collide_at(k, s.p, s.colliders.cut(s.p), &mut x4, &mut v4);
    (x4, v4)
}

/// Stage A for row `j` into `dst`; for a row of the band, `own` is where it starts in
/// `out`, and whether the positions are final (no strain passes).
#[inline(always)]
fn stage_a<S: Isa>(
    sd: S,
    s: &Step<'_>,
    input: &Ring,
    dst: &mut Ring,
    j: usize,
    own: Option<(usize, bool)>,
    out: &mut Next<'_>,
) {
    let p = s.p;
    let n = p.n as usize;
    let base = j * n;
    let put = |dst: &mut Ring, out: &mut Next<'_>, i: usize, (x4, v4): (V4, V4)| {
        dst.put4(j, 0, i, x4);
        for (c, vc) in v4.iter().take(3).enumerate() {
            dst.set(j, 4 + c, i, *vc);
        }
        if let Some((o, true)) = own {
            out.put(VEL, 3, o + i, v4);
            out.put(POS, 4, o + i, x4);
        }
    };
    let (g, drag) = forces_consts(p);
    let zero = F::splat(sd, 0.0);
    let tiny = F::splat(sd, f32::MIN_POSITIVE);
    let (gl, dragl) = ([F::splat(sd, g.x), F::splat(sd, g.y), F::splat(sd, g.z)], F::splat(sd, drag));
    let (keep, kick) = (F::splat(sd, 1.0 - p.damping), F::splat(sd, p.dt / p.particle_mass));
    let dtl = F::splat(sd, p.dt);
    let floor = F::splat(sd, p.floor_y + p.margin);
    let lanes = S::F32_LANES;

    // Every row in lanes: the rows near the top and bottom skip the slots that would
    // leave the grid, as the twins do; the lane groups at the edge columns mask them out
    // (adding +0, as a dead spring does: the twins' sums are kept bit for bit).
    for i0 in groups(0, n, lanes) {
        let edge = i0 < 2 || i0 + lanes + 2 > n;
        let xa = input.lanes3(sd, j, 0, i0);
        let va = input.lanes3(sd, j, 4, i0);
        let w = input.lanes(sd, j, 3, i0);
        let mut acc = input.lanes3(sd, j, 7, i0);
        for c in 0..3 {
            acc[c] = (acc[c] + gl[c]) - va[c] * dragl;
        }
        for (sl, slot) in s.uni.iter().enumerate() {
            let (di, dj) = SLOT_OFFSETS[sl];
            let Some(row) = j.checked_add_signed(dj as isize).filter(|&r| r < n) else { continue };
            let col = i0 as isize + di as isize;
            let xb = input.lanes3_at(sd, row, 0, col);
            let vb = input.lanes3_at(sd, row, 4, col);
            let l = [xa[0] - xb[0], xa[1] - xb[1], xa[2] - xb[2]];
            let dv = [va[0] - vb[0], va[1] - vb[1], va[2] - vb[2]];
            let len = (l[0] * l[0] + l[1] * l[1] + l[2] * l[2]).sqrt();
            let inv = F::splat(sd, 1.0) / len;
            let dir = [l[0] * inv, l[1] * inv, l[2] * inv];
            let dot = dv[0] * dir[0] + dv[1] * dir[1] + dv[2] * dir[2];
            let m = -(F::splat(sd, slot.ks) * (len - F::splat(sd, slot.rest)) + F::splat(sd, slot.kd) * dot);
            let mut live = len.gt(tiny);
            if edge {
                live = live & in_grid(sd, col, n);
            }
            for c in 0..3 {
                acc[c] += F::select(live, m * dir[c], zero);
            }
        }
        // Verlet for every lane; lanes that are held, or end in the floor or a collider,
        // go through the twins' scalar code instead.
        let mut v = [va[0] * keep + acc[0] * kick, va[1] * keep + acc[1] * kick, va[2] * keep + acc[2] * kick];
        let mut x = [xa[0] + v[0] * dtl, xa[1] + v[1] * dtl, xa[2] + v[2] * dtl];
        let mut wo = w;
        let special = w.eq(zero) | x[1].lt(floor) | inside(sd, p, s.colliders, &x);
        let mut bits = if special.any() { special.bits() } else { 0 };
        let grab = p.grab_index as isize - (base + i0) as isize;
        if (0..lanes as isize).contains(&grab) {
            bits |= 1 << grab;
        }
        while bits != 0 {
            let k = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let (x4, v4) = finish_at(s, base + i0 + k, [acc[0].lane(k), acc[1].lane(k), acc[2].lane(k), 0.0]);
            for c in 0..3 {
                x[c].set_lane(k, x4[c]);
                v[c].set_lane(k, v4[c]);
            }
            wo.set_lane(k, x4[3]);
        }
        dst.store4(j, i0, &x, wo);
        for (c, vc) in v.iter().enumerate() {
            dst.store(j, 4 + c, i0, *vc);
        }
        if let Some((o, true)) = own {
            out.store(VEL, o + i0, &v);
            out.store(POS, o + i0, &[x[0], x[1], x[2], wo]);
        }
    }
    for i in leftover(0, n, lanes) {
        put(dst, out, i, a_scalar(s, base + i));
    }
}

/// Lanes whose column `col + lane` is in the grid (`0 .. n`).
#[inline(always)]
fn in_grid<S: Isa>(sd: S, col: isize, n: usize) -> M<S> {
    const IOTA: [f32; PAD] = [0., 1., 2., 3., 4., 5., 6., 7., 8., 9., 10., 11., 12., 13., 14., 15.];
    let c = F::load(sd, &IOTA, 0) + F::splat(sd, col as f32);
    c.gt(F::splat(sd, -1.0)) & c.lt(F::splat(sd, n as f32))
}

/// Lanes at `x` within a collider's bound grown by the margin ([`Shape::bound`]: a
/// sphere's or a box's by `collide`'s own test, a rod's or a body's a
/// ball holding it): the lanes the scalar `collide_at` then resolves. (Plain loops, no
/// closure: a closure is compiled outside the SIMD context and its intrinsics become
/// calls — measured 1.5× the substep at n = 512.)
#[inline(always)]
fn inside<S: Isa>(sd: S, p: &StepParams, c: super::collide::Colliders<'_>, x: &[F<S>; 3]) -> M<S> {
    let c = c.cut(p);
    let r = p.margin;
    let mut any = M::splat(sd, false);
    for b in c.bodies() {
        any = any | within(sd, b.bound(r), x);
    }
    for s in c.rods {
        any = any | within(sd, s.bound(r), x);
    }
    for s in c.spheres {
        any = any | within(sd, s.bound(r), x);
    }
    for s in c.boxes {
        any = any | within(sd, s.bound(r), x);
    }
    any
}

/// Lanes at `x` within bound `b`.
#[inline(always)]
fn within<S: Isa>(sd: S, b: Bound, x: &[F<S>; 3]) -> M<S> {
    match b {
        Bound::Ball { center: m, r } => {
            let d = [x[0] - F::splat(sd, m.x), x[1] - F::splat(sd, m.y), x[2] - F::splat(sd, m.z)];
            (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).lt(F::splat(sd, r * r))
        }
        Bound::Box { lo, hi } => {
            let mut all = M::splat(sd, true);
            for (k, xc) in x.iter().enumerate() {
                all = all & xc.gt(F::splat(sd, lo[k])) & xc.lt(F::splat(sd, hi[k]));
            }
            all
        }
    }
}

/// The position pinned particle `k` has after stage A (its old one, or the grab target),
/// which the strain passes read through the tethers.
#[inline(always)]
fn pin_at(s: &Step<'_>, k: usize) -> V4 {
    let q = s.pos(k);
    if k as i32 == s.p.grab_index {
        let t = s.p.grab_target;
        [t[0], t[1], t[2], q[3]]
    } else {
        q
    }
}

/// Mobility of the lanes from `(row, i)`: w, with the grabbed particle's lane at 0.
#[inline(always)]
fn mobility<S: Isa>(sd: S, src: &Ring, n: usize, grab: i32, row: usize, col: isize) -> F<S> {
    let mut w = src.lanes_at(sd, row, 3, col);
    let k = grab as isize - (row * n) as isize - col;
    if (0..S::F32_LANES as isize).contains(&k) {
        w.set_lane(k as usize, 0.0);
    }
    w
}

/// The strain pass's scalar path for particle `(i, j)`: the twin, reading the previous
/// stage `src` and the pass's counts `cnt` (neighbours are within a row; a tether's pin
/// anywhere is fixed: `pin_at`).
#[inline(always)]
fn strain_scalar(s: &Step<'_>, src: &Ring, cnt: &Ring, j: usize, i: usize) -> V4 {
    let n = s.p.n as usize;
    limit_at(j * n + i, s.p, &GridSlots { n, uni: s.uni }, s.tethers, RingFetch { s, src, j }, |k| {
        cnt.get(k / n, 0, k % n)
    })
}

/// Slot `sl`'s spring of the lanes from `(j, i0)` at `xi`: where its other ends are, the
/// vector to them, its length, and the lanes where it is over the limit (`stretch`; lanes
/// beyond the grid's edge masked out where `edge`); `None` where its row is outside the
/// grid. The count stage and the pass decide alike through it.
struct StrainSpring<S: Isa> {
    row: usize,
    col: isize,
    d: [F<S>; 3],
    len: F<S>,
    live: M<S>,
}

#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn strain_spring<S: Isa>(
    sd: S,
    src: &Ring,
    j: usize,
    i0: usize,
    xi: &[F<S>; 3],
    sl: usize,
    slot: &SpringSlot,
    stretch: f32,
    edge: bool,
) -> Option<StrainSpring<S>> {
    let n = src.width - 2 * PAD;
    let (di, dj) = SLOT_OFFSETS[sl];
    let row = j.checked_add_signed(dj as isize).filter(|&r| r < n)?;
    let col = i0 as isize + di as isize;
    let xb = src.lanes3_at(sd, row, 0, col);
    let d = [xb[0] - xi[0], xb[1] - xi[1], xb[2] - xi[2]];
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let mut live = len.gt(F::splat(sd, stretch * slot.rest));
    if edge {
        live = live & in_grid(sd, col, n);
    }
    Some(StrainSpring { row, col, d, len, live })
}

/// The counts of over-stretched springs of row `j` (`strain_count`) from the previous
/// stage `src` into `dst`.
#[inline(always)]
fn stage_count<S: Isa>(sd: S, s: &Step<'_>, src: &Ring, dst: &mut Ring, j: usize) {
    let p = s.p;
    let n = p.n as usize;
    let stretch = 1.0 + p.strain_limit;
    let zero = F::splat(sd, 0.0);
    let one = F::splat(sd, 1.0);
    let lanes = S::F32_LANES;
    for i0 in groups(0, n, lanes) {
        let edge = i0 < 2 || i0 + lanes + 2 > n;
        let xi = src.lanes3(sd, j, 0, i0);
        let mut count = zero;
        for (sl, slot) in s.uni[..STRAIN_SLOTS].iter().enumerate() {
            if let Some(sp) = strain_spring(sd, src, j, i0, &xi, sl, slot, stretch, edge) {
                count += F::select(sp.live, one, zero);
            }
        }
        dst.store(j, 0, i0, count);
    }
    for i in leftover(0, n, lanes) {
        let c = count_at(j * n + i, p, &GridSlots { n, uni: s.uni }, RingFetch { s, src, j });
        dst.set(j, 0, i, c);
    }
}

/// One strain-limit pass for row `j`, from the previous stage `src` into `dst` (and,
/// for the band's own rows after the last pass, `out`).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn stage_strain<S: Isa>(
    sd: S,
    s: &Step<'_>,
    src: &Ring,
    cnt: &Ring,
    dst: &mut Ring,
    j: usize,
    own: Option<usize>,
    out: &mut Next<'_>,
) {
    let p = s.p;
    let n = p.n as usize;
    let base = j * n;
    let inv_dt = 1.0 / p.dt;
    let put = |dst: &mut Ring, out: &mut Next<'_>, i: usize, x4: V4| {
        let v0 = [src.get(j, 4, i), src.get(j, 5, i), src.get(j, 6, i), 0.0];
        let v4 = moved_vel(v0, src.get4(j, 0, i), x4, inv_dt);
        dst.put4(j, 0, i, x4);
        for (c, vc) in v4.iter().take(3).enumerate() {
            dst.set(j, 4 + c, i, *vc);
        }
        if let Some(o) = own {
            out.put(POS, 4, o + i, x4);
            out.put(VEL, 3, o + i, v4);
        }
    };
    let inv_dtl = F::splat(sd, inv_dt);
    let stretch = 1.0 + p.strain_limit;
    let aim = 1.0 + STRAIN_AIM * p.strain_limit;
    let zero = F::splat(sd, 0.0);
    let one = F::splat(sd, 1.0);
    let lanes = S::F32_LANES;

    for i0 in groups(0, n, lanes) {
        let edge = i0 < 2 || i0 + lanes + 2 > n;
        let xi = src.lanes3(sd, j, 0, i0);
        let wi = mobility(sd, src, n, p.grab_index, j, i0 as isize);
        let ci = cnt.lanes(sd, j, 0, i0);
        let mut corr = [zero; 3];
        let mut count = zero;
        // Lanes whose counts are all 0 have no spring over its limit (the counts are this
        // pass's, found as the pass finds them): nothing to add (limit_at skips them alike).
        let springs = if ci.gt(zero).any() { &s.uni[..STRAIN_SLOTS] } else { &[][..] };
        for (sl, slot) in springs.iter().enumerate() {
            let Some(StrainSpring { row, col, d, len, live }) =
                strain_spring(sd, src, j, i0, &xi, sl, slot, stretch, edge)
            else {
                continue;
            };
            let wb = mobility(sd, src, n, p.grab_index, row, col);
            let m = ci.max(cnt.lanes_at(sd, row, 0, col)).max(one);
            let f = wi * (len - F::splat(sd, aim * slot.rest)) / ((wi + wb) * len * m);
            for c in 0..3 {
                corr[c] += F::select(live, d[c] * f, zero);
            }
            count += F::select(live, one, zero);
        }
        let has = count.gt(zero);
        let mut x = [
            F::select(has, xi[0] + corr[0], xi[0]),
            F::select(has, xi[1] + corr[1], xi[1]),
            F::select(has, xi[2] + corr[2], xi[2]),
        ];
        for t in 0..TETHER_SLOTS {
            let pins = &s.tether_lanes.pin[t][base + i0..base + i0 + lanes];
            let first = pins[0];
            let same = pins.iter().fold(true, |a, &q| a & (q == first));
            if same && first < 0 {
                continue;
            }
            // Most groups hold to one pin (all of a corner's side of the sheet); others
            // gather, empty slots reading particle 0, masked out.
            let (pin, live) = if same {
                let q = pin_at(s, first as usize);
                ([F::splat(sd, q[0]), F::splat(sd, q[1]), F::splat(sd, q[2])], M::splat(sd, true))
            } else {
                let mut pin = [zero; 3];
                let mut held = zero;
                for (k, &q) in pins.iter().enumerate() {
                    let x4 = pin_at(s, q.max(0) as usize);
                    for c in 0..3 {
                        pin[c].set_lane(k, x4[c]);
                    }
                    held.set_lane(k, (q >= 0) as u8 as f32);
                }
                (pin, held.gt(zero))
            };
            let rest = F::load(sd, &s.tether_lanes.rest[t], base + i0);
            let d = [x[0] - pin[0], x[1] - pin[1], x[2] - pin[2]];
            let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let max = F::splat(sd, stretch) * rest;
            let apply = len.gt(max) & live;
            let q = max / len;
            for c in 0..3 {
                x[c] = F::select(apply, pin[c] + d[c] * q, x[c]);
            }
        }
        // Pinned and grabbed particles keep their position.
        let fixed = wi.eq(zero);
        let x = [F::select(fixed, xi[0], x[0]), F::select(fixed, xi[1], x[1]), F::select(fixed, xi[2], x[2])];
        let w = src.lanes(sd, j, 3, i0);
        // The velocity the pass's move implies (strain_vel).
        let vi = src.lanes3(sd, j, 4, i0);
        let v: [F<S>; 3] = std::array::from_fn(|c| vi[c] + (x[c] - xi[c]) * inv_dtl);
        dst.store4(j, i0, &x, w);
        for (c, vc) in v.iter().enumerate() {
            dst.store(j, 4 + c, i0, *vc);
        }
        if let Some(o) = own {
            out.store(POS, o + i0, &[x[0], x[1], x[2], w]);
            out.store(VEL, o + i0, &v);
        }
    }
    for i in leftover(0, n, lanes) {
        put(dst, out, i, strain_scalar(s, src, cnt, j, i));
    }
}

/// `tri_normals` for quad row `q` from the final positions `src` into `faces`.
#[inline(always)]
fn stage_tri<S: Isa>(sd: S, n: usize, src: &Ring, faces: &mut Ring, q: usize) {
    let m = n - 1;

    for qi in groups(0, m, S::F32_LANES) {
        let p00 = src.lanes3(sd, q, 0, qi);
        let p10 = src.lanes3(sd, q, 0, qi + 1);
        let p01 = src.lanes3(sd, q + 1, 0, qi);
        let p11 = src.lanes3(sd, q + 1, 0, qi + 1);
        for (c, v) in cross_len(&p00, &p01, &p11).into_iter().chain(cross_len(&p00, &p11, &p10)).enumerate() {
            faces.store(q, c, qi, v);
        }
    }
    let at = |r: usize, i: usize| Vec3::new(src.get(r, 0, i), src.get(r, 1, i), src.get(r, 2, i));
    for qi in leftover(0, m, S::F32_LANES) {
        let [t0, t1] = quad_normals(at(q, qi), at(q, qi + 1), at(q + 1, qi), at(q + 1, qi + 1));
        faces.put4(q, 0, qi, t0);
        faces.put4(q, 4, qi, t1);
    }
}

/// `vertex_normals` for row `r` from the face normals of quad rows `r − 1` and `r`.
#[inline(always)]
fn stage_vert<S: Isa>(sd: S, s: &Step<'_>, faces: &Ring, r: usize, o: usize, out: &mut Next<'_>) {
    let p = s.p;
    let n = p.n as usize;
    let m = n - 1;
    let w = v3(p.wind);
    let c = p.wind[3] / 6.0;
    let face = FaceFetch { faces, m };
    // A function, not a closure: closures were left out of line, in baseline code.
    #[inline(always)]
    fn scalar(
        s: &Step<'_>,
        face: FaceFetch<'_>,
        (r, o, w, c): (usize, usize, Vec3, f32),
        out: &mut Next<'_>,
        i: usize,
    ) {
        let n = s.p.n as usize;
        let (nrm, wind) = vnormal_at(s.face_slots.row(r * n + i), face, w, c);
        out.put(NORMAL, 3, o + i, nrm);
        out.put(FORCE, 3, o + i, wind);
    }
    let scalar = |out: &mut Next<'_>, i: usize| scalar(s, face, (r, o, w, c), out, i);
    if !(r >= 1 && r + 1 < n) {
        for i in 0..n {
            scalar(out, i);
        }
        return;
    }
    scalar(out, 0);
    let lanes = S::F32_LANES;
    for i0 in groups(1, n - 1, lanes) {
        // Quads (i−1, r−1), (i, r−1), (i−1, r), (i, r), in the order of the face slots.
        let faces6 = [
            faces_lanes(sd, faces, r - 1, 0, i0 - 1),
            faces_lanes(sd, faces, r - 1, 4, i0 - 1),
            faces_lanes(sd, faces, r - 1, 0, i0),
            faces_lanes(sd, faces, r, 4, i0 - 1),
            faces_lanes(sd, faces, r, 0, i0),
            faces_lanes(sd, faces, r, 4, i0),
        ];
        let (nv, wind) = vnormal_lanes(sd, &faces6, w, c);
        out.store(NORMAL, o + i0, &nv);
        out.store(FORCE, o + i0, &wind);
    }
    for i in leftover(1, n - 1, lanes).chain([n - 1]) {
        scalar(out, i);
    }
}

#[inline(always)]
fn faces_lanes<S: Isa>(sd: S, faces: &Ring, q: usize, c0: usize, qi: usize) -> [F<S>; 4] {
    [
        faces.lanes(sd, q, c0, qi),
        faces.lanes(sd, q, c0 + 1, qi),
        faces.lanes(sd, q, c0 + 2, qi),
        faces.lanes(sd, q, c0 + 3, qi),
    ]
}
