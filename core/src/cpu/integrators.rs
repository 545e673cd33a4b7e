//! The integrators other than Verlet (thesis §4.1.1–4.1.2), one function per GPU kernel.
//!
//! Every integrator keeps its state in Verlet's two buffers: `prev = x − u` with
//! `u = v·dt`, the velocity as a displacement per substep. The force kernels read
//! `x − prev` as `v·dt`, so `forces`, `springs` and their fused and scattered forms
//! evaluate the force for every integrator unchanged; the integrators differ only in
//! where they evaluate it and how they combine the results. Working in displacements
//! (`u`, and `g = f·dt²/m` for the force) needs no division by dt anywhere.
//!
//! Scratch state lives in [`AUX`] particle buffers (`aux`), whose meaning depends on the
//! integrator:
//!
//! | buffer | RK2, RK4 | implicit |
//! |---|---|---|
//! | `aux[0]` | `x₀` (w: pin flag) | `Δu`, the Newton step |
//! | `aux[1]` | `u₀` (damped) | `r` (w: the Jacobi preconditioner's diagonal) |
//! | `aux[2]` | `Σ bₛ uₛ` | `p` |
//! | `aux[3]` | `Σ bₛ gₛ` | `q = A p` |
//! | `aux[4]` | the substep's wind force | — |
//!
//! XPBD keeps each spring's λ at the spring's first end: slots 1, 3, 7 in `aux[0]`'s x,
//! y, z and slots 6, 9, 11 in `aux[1]`'s (cleared at every substep's start).
//!
//! Pins, the grab and the floor end every integrator's substep as [`super::integrate`]
//! ends Verlet's (`finish_at`); spheres and boxes are the `collide` kernel's, run after.

use glam::Vec3;
use rayon::prelude::*;

use super::integrate::contact_prev;
use super::{Exec, v3, v4};
use crate::grid::{SLOTS, SpringSlot, StepParams, V4};

/// Scratch particle buffers the integrators use.
pub const AUX: usize = 5;

/// The conjugate-gradient scalars (a `vec4<f32>` on the GPU): `r·z`, `p·q`, `α`, `β`.
pub type CgScalars = [f32; 4];

/// One stage of an explicit Runge–Kutta method in the kernels' form: the stage's force
/// is in the force buffer; `b` is its weight in the final sum, `c_next` where the next
/// stage evaluates (`x₀ + c_next·dt·k`). The first stage starts the sum, the last one
/// ends the substep.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RkStage {
    /// The next stage's point, in substeps from the start.
    pub c_next: f32,
    /// The stage's weight.
    pub b: f32,
    /// Starts the weighted sum (else adds to it).
    pub first: bool,
    /// Ends the substep.
    pub last: bool,
}

/// The midpoint method: `k₁ = f(y₀)`, `k₂ = f(y₀ + dt/2·k₁)`, `y₁ = y₀ + dt·k₂`.
pub const RK2: [RkStage; 2] = [
    RkStage { c_next: 0.5, b: 0.0, first: true, last: false },
    RkStage { c_next: 0.0, b: 1.0, first: false, last: true },
];

/// Classical RK4: weights 1/6, 1/3, 1/3, 1/6 at 0, 1/2, 1/2, 1.
pub const RK4: [RkStage; 4] = [
    RkStage { c_next: 0.5, b: 1.0 / 6.0, first: true, last: false },
    RkStage { c_next: 0.5, b: 1.0 / 3.0, first: false, last: false },
    RkStage { c_next: 1.0, b: 1.0 / 3.0, first: false, last: false },
    RkStage { c_next: 0.0, b: 1.0 / 6.0, first: false, last: true },
];

/// `f(i)` for every particle, in parallel or not (each result depends on `i` only, so
/// both give the same bits).
fn per_particle<T: Send>(exec: Exec, count: usize, f: impl Fn(usize) -> T + Sync + Send) -> Vec<T> {
    match exec {
        Exec::Serial => (0..count).map(f).collect(),
        Exec::Parallel => (0..count).into_par_iter().with_min_len(1024).map(f).collect(),
    }
}

/// Whether particle `i` at `x4` is held (pinned or grabbed): it does not integrate.
#[inline(always)]
fn held(i: usize, p: &StepParams, x4: V4) -> bool {
    i as i32 == p.grab_index || x4[3] == 0.0
}

/// The end of a substep for particle `i` at `x4` that integrates to `x1` with velocity
/// displacement `u1`: the new `(pos, prev)` with the pins, the grab and the floor handled
/// as [`super::integrate`] handles them.
#[inline(always)]
pub(crate) fn finish_at(i: usize, p: &StepParams, x4: V4, x1: Vec3, u1: Vec3) -> (V4, V4) {
    let x = v3(x4);
    if i as i32 == p.grab_index {
        return (v4(v3(p.grab_target), x4[3]), v4(x, 0.0));
    }
    if x4[3] == 0.0 {
        return (x4, v4(x, 0.0));
    }
    let mut xn = x1;
    let mut xp = x1 - u1;
    let floor = p.floor_y + p.margin;
    if xn.y < floor {
        xn.y = floor;
        xp = contact_prev(xn, xp, Vec3::Y, p.friction);
    }
    (v4(xn, x4[3]), v4(xp, 0.0))
}

/// `f·dt²/m`: a force as the displacement it adds in one substep.
#[inline(always)]
fn accel_dt2(p: &StepParams, f: V4) -> Vec3 {
    v3(f) * (p.dt * p.dt / p.particle_mass)
}

/// Explicit Euler: `x' = x + u`, `u' = u + g`, with `u = (1 − damping)(x − prev)`.
///
/// (Symplectic Euler, `u' = u + g`, `x' = x + u'`, needs no kernel of its own: in this
/// state it is `x' = x + u + g`, `prev' = x` — Verlet's recurrence, step for step, so
/// Verlet's kernels run it. The two differ in how a state with a velocity is read: Verlet
/// takes `prev` as `x(t − dt)`, symplectic Euler as `x − v·dt`, which makes one second-
/// and the other first-order in the positions from a given `(x, v)`.)
pub fn euler(exec: Exec, p: &StepParams, force: &[V4], pos: &mut [V4], prev: &mut [V4]) {
    let out = per_particle(exec, pos.len(), |i| {
        let x = v3(pos[i]);
        let u0 = (x - v3(prev[i])) * (1.0 - p.damping);
        let u1 = u0 + accel_dt2(p, force[i]);
        finish_at(i, p, pos[i], x + u0, u1)
    });
    for (i, (x, xp)) in out.into_iter().enumerate() {
        pos[i] = x;
        prev[i] = xp;
    }
}

/// The start of a Runge–Kutta substep: saves `x₀`, the damped `u₀` and the wind force
/// (which the force kernels add to), and writes `prev = x₀ − u₀` so that the first force
/// evaluation sees the damped velocity.
pub fn rk_begin(exec: Exec, p: &StepParams, force: &[V4], pos: &[V4], prev: &mut [V4], aux: &mut [Vec<V4>]) {
    let out = per_particle(exec, pos.len(), |i| {
        let x = v3(pos[i]);
        let u0 = (x - v3(prev[i])) * (1.0 - p.damping);
        (v4(u0, 0.0), v4(x - u0, 0.0))
    });
    for (i, (u0, xp)) in out.into_iter().enumerate() {
        aux[0][i] = pos[i];
        aux[1][i] = u0;
        aux[4][i] = force[i];
        prev[i] = xp;
    }
}

/// One Runge–Kutta stage (see [`RkStage`]): adds the stage's `(u, g)` to the weighted
/// sum, then either puts the particles at the next stage's point (velocity in `prev`, the
/// wind back in the force buffer) or ends the substep at `y₀ + Σ bₛ kₛ`.
pub fn rk_stage(
    exec: Exec,
    p: &StepParams,
    st: &RkStage,
    force: &mut [V4],
    pos: &mut [V4],
    prev: &mut [V4],
    aux: &mut [Vec<V4>],
) {
    let out = per_particle(exec, pos.len(), |i| {
        let x4 = pos[i];
        // The first stage evaluates at y₀: its u is the saved one, exactly.
        let us = if st.first { v3(aux[1][i]) } else { v3(x4) - v3(prev[i]) };
        let gs = accel_dt2(p, force[i]);
        let (sx, su) =
            if st.first { (us * st.b, gs * st.b) } else { (v3(aux[2][i]) + us * st.b, v3(aux[3][i]) + gs * st.b) };
        let (x0, u0) = (v3(aux[0][i]), v3(aux[1][i]));
        let (x, xp) = if st.last {
            finish_at(i, p, x4, x0 + sx, u0 + su)
        } else if held(i, p, x4) {
            (x4, v4(v3(x4), 0.0))
        } else {
            let x = x0 + us * st.c_next;
            let u = u0 + gs * st.c_next;
            (v4(x, x4[3]), v4(x - u, 0.0))
        };
        (x, xp, v4(sx, 0.0), v4(su, 0.0))
    });
    for (i, (x, xp, sx, su)) in out.into_iter().enumerate() {
        pos[i] = x;
        prev[i] = xp;
        aux[2][i] = sx;
        aux[3][i] = su;
        if !st.last {
            force[i] = aux[4][i];
        }
    }
}

/// Mobility of particle `k` at `x4`: 0 when pinned or grabbed, else its flag (1).
#[inline(always)]
fn mobility(k: usize, p: &StepParams, x4: V4) -> f32 {
    if k as i32 == p.grab_index { 0.0 } else { x4[3] }
}

/// The passes of one XPBD iteration: (forward slot, colour). Every spring of the grid is
/// the forward slot (offset `(1,0)`, `(0,1)`, `(1,1)`, `(−1,1)`, `(2,0)` or `(0,2)`) of
/// exactly one particle `a`; within one direction, the springs of the particles of one
/// colour share no particle, so a pass solves them all at once with no conflicts, and the
/// 12 passes one after another are Gauss–Seidel over the colours.
pub const XPBD_PASSES: [(usize, u32); 12] =
    [(1, 0), (1, 1), (3, 0), (3, 1), (7, 0), (7, 1), (6, 0), (6, 1), (9, 0), (9, 1), (11, 0), (11, 1)];

/// The order one XPBD iteration runs the passes of [`XPBD_PASSES`] in: bend springs, then
/// shear, then structural, so that an iteration ends with the springs the strain is
/// measured on. Measured (physical stiffness, the default scene draped for 1600 substeps,
/// cpu-par): in the passes' own order (structural first) the bend passes that came last
/// left every fourth structural spring of a row stretched (the bend colouring's period),
/// max strain 0.131 / 0.243 at n = 128 / 256 with one iteration and 0.165 at n = 512 with
/// four iterations and four strain passes; in this order 0.106 / 0.136 and 0.146, the
/// worst springs now beside the pins.
pub const XPBD_ORDER: [usize; 12] = [8, 9, 10, 11, 4, 5, 6, 7, 0, 1, 2, 3];

/// The colour of particle `(i, j)` for the springs of slot `s`: the parity of its
/// coordinate along the spring, in steps of the spring's length (1, or 2 for bend springs),
/// so that the spring before it along that line has the other colour.
#[inline(always)]
pub fn xpbd_colour(s: usize, i: u32, j: u32) -> u32 {
    let (di, dj) = crate::grid::SLOT_OFFSETS[s];
    let (key, step) = if di != 0 { (i, di.unsigned_abs()) } else { (j, dj.unsigned_abs()) };
    (key / step) % 2
}

/// Where pass `pass` keeps its springs' λ: (`aux` buffer, component).
pub fn xpbd_lambda_home(pass: usize) -> (usize, usize) {
    (pass / 6, (pass / 2) % 3)
}

/// One XPBD pass (see [`XPBD_PASSES`]): every spring in slot `s` of a particle of colour
/// `colour` with `ks > 0` is a distance constraint `C = |x_a − x_b| − rest` of compliance
/// `α̃ = 1/(ks·dt²)` and damping `γ = kd/(ks·dt)`, its λ kept in `lambda` (XPBD's eq. 26;
/// λ starts at zero every substep), solved for both ends by their mobilities, in place.
/// `prev` holds where the substep began.
pub fn xpbd_pass(
    p: &StepParams,
    slots: &[SpringSlot],
    pass: usize,
    pos: &mut [V4],
    prev: &[V4],
    lambda: &mut [Vec<V4>],
) {
    let (buf, c) = xpbd_lambda_home(pass);
    for a in 0..pos.len() {
        let Some((slot, b)) = pass_spring(p, slots, pass, a) else { continue };
        let l = lambda[buf][a][c];
        if let Some((xa, xb, dl)) = xpbd_solve(p, &slot, a, b, pos[a], pos[b], prev[a], prev[b], l) {
            pos[a] = xa;
            pos[b] = xb;
            lambda[buf][a][c] = l + dl;
        }
    }
}

/// The spring pass `pass` solves at particle `a` (its first end), if any: the slot and
/// the other end.
#[inline(always)]
fn pass_spring(p: &StepParams, slots: &[SpringSlot], pass: usize, a: usize) -> Option<(SpringSlot, usize)> {
    let (s, colour) = XPBD_PASSES[pass];
    let n = p.n as usize;
    if xpbd_colour(s, (a % n) as u32, (a / n) as u32) != colour {
        return None;
    }
    let slot = slots[a * SLOTS + s];
    (slot.neighbor >= 0 && slot.ks > 0.0).then_some((slot, slot.neighbor as usize))
}

/// [`xpbd_pass`] on rayon's threads, for a grid whose every spring points at its slot's
/// offset ([`crate::grid::ClothTopology::grid_slots`] is `Some`). The pass's springs share
/// no particle, so the order they are solved in changes no bit; they are solved in blocks
/// of rows that own both ends of their springs: a row each for the horizontal slots, and
/// for a slot reaching `dj` rows down, blocks of `2·dj` rows whose first `dj` rows hold the
/// springs' first ends, in two phases (the blocks starting at row 0, then at row `dj`).
pub fn xpbd_pass_rows(
    exec: Exec,
    p: &StepParams,
    slots: &[SpringSlot],
    pass: usize,
    pos: &mut [V4],
    prev: &[V4],
    lambda: &mut [Vec<V4>],
) {
    let (buf, c) = xpbd_lambda_home(pass);
    let n = p.n as usize;
    let dj = crate::grid::SLOT_OFFSETS[XPBD_PASSES[pass].0].1.unsigned_abs() as usize;
    let (block, firsts, phases) = if dj == 0 { (1, 1, 1) } else { (2 * dj, dj, 2) };
    for phase in 0..phases {
        let skip = phase * dj * n;
        let solve = |(k, (xs, ls)): (usize, (&mut [V4], &mut [V4]))| {
            let start = skip + k * block * n;
            for r in 0..firsts.min(xs.len() / n) {
                for a in start + r * n..start + (r + 1) * n {
                    let Some((slot, b)) = pass_spring(p, slots, pass, a) else { continue };
                    let (la, lb) = (a - start, b - start);
                    let l = ls[la][c];
                    if let Some((xa, xb, dl)) = xpbd_solve(p, &slot, a, b, xs[la], xs[lb], prev[a], prev[b], l) {
                        xs[la] = xa;
                        xs[lb] = xb;
                        ls[la][c] = l + dl;
                    }
                }
            }
        };
        let (xs, ls) = (&mut pos[skip..], &mut lambda[buf][skip..]);
        match exec {
            Exec::Serial => xs.chunks_mut(block * n).zip(ls.chunks_mut(block * n)).enumerate().for_each(solve),
            Exec::Parallel => {
                xs.par_chunks_mut(block * n).zip(ls.par_chunks_mut(block * n)).enumerate().for_each(solve)
            }
        }
    }
}

/// The constraint of `slot` between `a` (at `xa4`) and `b` with multiplier `l`: their
/// new positions and Δλ, or `None` when neither moves.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn xpbd_solve(
    p: &StepParams,
    slot: &SpringSlot,
    a: usize,
    b: usize,
    xa4: V4,
    xb4: V4,
    pa: V4,
    pb: V4,
    l: f32,
) -> Option<(V4, V4, f32)> {
    let inv_m = 1.0 / p.particle_mass;
    let (wa, wb) = (mobility(a, p, xa4) * inv_m, mobility(b, p, xb4) * inv_m);
    if wa + wb == 0.0 {
        return None;
    }
    let (xa, xb) = (v3(xa4), v3(xb4));
    let d = xa - xb;
    let len = d.length();
    if len <= f32::MIN_POSITIVE {
        return None;
    }
    let n = d * (1.0 / len);
    let alpha = 1.0 / (slot.ks * p.dt * p.dt);
    let gamma = slot.kd / (slot.ks * p.dt);
    let rel = n.dot((xa - v3(pa)) - (xb - v3(pb)));
    let dl = -((len - slot.rest) + alpha * l + gamma * rel) / ((1.0 + gamma) * (wa + wb) + alpha);
    Some((v4(xa + n * (dl * wa), xa4[3]), v4(xb - n * (dl * wb), xb4[3]), dl))
}

// ---- implicit Euler: one Newton step, preconditioned conjugate gradients -------------
//
// In displacements (Δu = Δv·dt, u₀ = v₀·dt) the Newton step of backward Euler is
// `A Δu = dt²(f₀ − K u₀)`, `A = m(1 + dt·drag) I + Σₛ (dt² Kₛ + dt Dₛ)` over the springs,
// with `Kₛ = ks [n nᵀ + max(0, 1 − rest/len)(I − n nᵀ)]` (the stiffness Jacobian with its
// compressive part dropped, so that A is positive definite: Choi & Ko 2002) and
// `Dₛ = kd n nᵀ`. Held particles are filtered out (Baraff & Witkin's modified PCG: their
// rows of r, p and q are zero). The preconditioner is the diagonal of A (a third of each
// block's trace).

/// `(dt² Kₛ + dt Dₛ) y` (without `Dₛ` unless `with_damping`) for the spring from `xa` to
/// `xb`, and a third of the trace of `dt² Kₛ + dt Dₛ`.
#[inline(always)]
fn spring_block(p: &StepParams, s: &SpringSlot, xa: Vec3, xb: Vec3, y: Vec3, with_damping: bool) -> (Vec3, f32) {
    let d = xa - xb;
    let len = d.length();
    if len <= f32::MIN_POSITIVE {
        return (Vec3::ZERO, 0.0);
    }
    let n = d * (1.0 / len);
    let soft = (1.0 - s.rest / len).max(0.0);
    let ny = n.dot(y);
    let k2 = s.ks * p.dt * p.dt;
    let c = if with_damping { s.kd * p.dt } else { 0.0 };
    let v = n * ((k2 + c) * ny) + (y - n * ny) * (k2 * soft);
    (v, (k2 * (1.0 + 2.0 * soft) + s.kd * p.dt) / 3.0)
}

/// `(A y)ᵢ` (or, without damping and mass, `dt² (K y)ᵢ`) over particle `i`'s slots, and
/// the diagonal of A.
#[inline(always)]
fn apply_at(
    i: usize,
    p: &StepParams,
    slots: &[SpringSlot],
    pos: &[V4],
    y: &dyn Fn(usize) -> Vec3,
    full: bool,
) -> (Vec3, f32) {
    let xa = v3(pos[i]);
    let ya = y(i);
    let m = p.particle_mass * (1.0 + p.dt * p.air_drag);
    let (mut acc, mut diag) = if full { (ya * m, m) } else { (Vec3::ZERO, m) };
    for s in &slots[i * SLOTS..(i + 1) * SLOTS] {
        if s.neighbor < 0 {
            continue;
        }
        let b = s.neighbor as usize;
        let (v, tr) = spring_block(p, s, xa, v3(pos[b]), ya - y(b), full);
        acc += v;
        diag += tr;
    }
    (acc, diag)
}

/// `z = r / diag` (zero where the diagonal is, for held particles).
#[inline(always)]
fn precondition(r4: V4) -> Vec3 {
    if r4[3] > 0.0 { v3(r4) / r4[3] } else { Vec3::ZERO }
}

/// The sums of `terms` per workgroup of particles (as the GPU kernels leave them, one per
/// workgroup, in `aux[4]`; within a workgroup the GPU adds in a tree, here in order).
pub fn partial_sums(terms: &[f32]) -> Vec<f32> {
    terms.chunks(crate::layout::WORKGROUP as usize).map(|c| c.iter().sum()).collect()
}

/// The reduction kernels' fold of the partial sums.
pub fn fold(partials: &[f32]) -> f32 {
    partials.iter().sum()
}

/// Starts the solve from the force `f₀` in `force`: `Δu = 0`, `r = dt²(f₀ − K u₀)` (w: the
/// diagonal), `p = z = r/diag`; returns `r·z`.
pub fn cg_begin(
    exec: Exec,
    p: &StepParams,
    slots: &[SpringSlot],
    force: &[V4],
    pos: &[V4],
    prev: &[V4],
    aux: &mut [Vec<V4>],
) -> Vec<f32> {
    let u = |k: usize| v3(pos[k]) - v3(prev[k]);
    let out = per_particle(exec, pos.len(), |i| {
        let (ku, diag) = apply_at(i, p, slots, pos, &u, false);
        let r = if held(i, p, pos[i]) { Vec3::ZERO } else { v3(force[i]) * (p.dt * p.dt) - ku };
        let r4 = v4(r, diag);
        let z = precondition(r4);
        (r4, z, r.dot(z))
    });
    let mut terms = Vec::with_capacity(out.len());
    for (i, (r4, z, rz)) in out.into_iter().enumerate() {
        aux[0][i] = [0.0; 4];
        aux[1][i] = r4;
        aux[2][i] = v4(z, 0.0);
        terms.push(rz);
    }
    terms
}

/// `q = S A p` (zero for held particles); returns the terms of `p·q`.
pub fn cg_matvec(exec: Exec, p: &StepParams, slots: &[SpringSlot], pos: &[V4], aux: &mut [Vec<V4>]) -> Vec<f32> {
    let dir = &aux[2];
    let y = |k: usize| v3(dir[k]);
    let out = per_particle(exec, pos.len(), |i| {
        let q = if held(i, p, pos[i]) { Vec3::ZERO } else { apply_at(i, p, slots, pos, &y, true).0 };
        (q, y(i).dot(q))
    });
    let mut terms = Vec::with_capacity(out.len());
    for (i, (q, pq)) in out.into_iter().enumerate() {
        aux[3][i] = v4(q, 0.0);
        terms.push(pq);
    }
    terms
}

/// After `p·q`: `α = r·z / p·q` (0 when `p·q` is not positive: the solve has converged).
pub fn cg_alpha(s: &mut CgScalars, pq: f32) {
    s[1] = pq;
    s[2] = if pq > 0.0 { s[0] / pq } else { 0.0 };
}

/// `Δu += α p`, `r −= α q`; returns the terms of the new `r·z`.
pub fn cg_step(exec: Exec, s: &CgScalars, aux: &mut [Vec<V4>]) -> Vec<f32> {
    let alpha = s[2];
    let out = per_particle(exec, aux[0].len(), |i| {
        let x = v3(aux[0][i]) + v3(aux[2][i]) * alpha;
        let r = v3(aux[1][i]) - v3(aux[3][i]) * alpha;
        let r4 = v4(r, aux[1][i][3]);
        (x, r4, r.dot(precondition(r4)))
    });
    let mut terms = Vec::with_capacity(out.len());
    for (i, (x, r4, rz)) in out.into_iter().enumerate() {
        aux[0][i] = v4(x, 0.0);
        aux[1][i] = r4;
        terms.push(rz);
    }
    terms
}

/// After a new `r·z`: `β = new / old` (0 when the old one was not positive), then the new
/// one is kept.
pub fn cg_beta(s: &mut CgScalars, rz: f32) {
    s[3] = if s[0] > 0.0 { rz / s[0] } else { 0.0 };
    s[0] = rz;
}

/// `p = z + β p`.
pub fn cg_direction(exec: Exec, s: &CgScalars, aux: &mut [Vec<V4>]) {
    let beta = s[3];
    let out = per_particle(exec, aux[0].len(), |i| precondition(aux[1][i]) + v3(aux[2][i]) * beta);
    for (i, d) in out.into_iter().enumerate() {
        aux[2][i] = v4(d, 0.0);
    }
}

/// Ends the implicit substep: `u₁ = (1 − damping) u₀ + Δu`, `x₁ = x₀ + u₁`.
pub fn implicit_finish(exec: Exec, p: &StepParams, pos: &mut [V4], prev: &mut [V4], aux: &[Vec<V4>]) {
    let out = per_particle(exec, pos.len(), |i| {
        let x = v3(pos[i]);
        let u1 = (x - v3(prev[i])) * (1.0 - p.damping) + v3(aux[0][i]);
        finish_at(i, p, pos[i], x + u1, u1)
    });
    for (i, (x, xp)) in out.into_iter().enumerate() {
        pos[i] = x;
        prev[i] = xp;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::build;
    use crate::{Scene, SimParams};

    #[test]
    fn the_xpbd_passes_solve_every_spring_once_and_no_pass_touches_a_particle_twice() {
        // Grids with odd and even sides, and sides not a multiple of the bend springs' 4.
        for n in [5u32, 8, 13] {
            let (_, topo) = build(&Scene::with_n(n), &SimParams::default()).unwrap();
            let mut solved = 0;
            for &(s, colour) in &XPBD_PASSES {
                let mut touched = vec![false; topo.num_particles()];
                for a in 0..topo.num_particles() {
                    let slot = topo.slots[a * SLOTS + s];
                    if slot.neighbor < 0 || xpbd_colour(s, a as u32 % n, a as u32 / n) != colour {
                        continue;
                    }
                    for k in [a, slot.neighbor as usize] {
                        assert!(!touched[k], "n = {n}, slot {s}, colour {colour}: particle {k} in two springs");
                        touched[k] = true;
                    }
                    solved += 1;
                }
            }
            assert_eq!(solved, topo.springs.len(), "n = {n}: every spring in exactly one pass");
        }
    }

    #[test]
    fn the_xpbd_passes_by_blocks_of_rows_are_the_serial_passes_bit_for_bit() {
        // Sides odd and even, below and above a bend block (4 rows); a stretched, jittered
        // cloth so that every constraint moves, and a grabbed particle.
        for n in [3u32, 5, 8, 13, 40] {
            let (st, topo) = build(&Scene::with_n(n), &SimParams::default()).unwrap();
            let params = SimParams::default();
            let grab = crate::grid::Grab { particle: n + 1, target: [0.1, 2.0, 0.3] };
            let p = StepParams::new(&params, &Scene::with_n(n), Some(grab));
            let jitter = |k: usize, c: usize| ((k * 7919 + c * 104729) % 1000) as f32 * 1e-4;
            let pos: Vec<V4> = st
                .pos
                .iter()
                .enumerate()
                .map(|(k, x)| [x[0] * 1.3 + jitter(k, 0), x[1] + jitter(k, 1), x[2] * 1.2, x[3]])
                .collect();
            let prev: Vec<V4> =
                pos.iter().enumerate().map(|(k, x)| [x[0] - jitter(k, 2), x[1], x[2] + jitter(k, 1), 0.0]).collect();
            let run = |exec: Option<Exec>| {
                let (mut x, mut lambda) = (pos.clone(), vec![vec![[0.0f32; 4]; pos.len()]; 2]);
                for _ in 0..2 {
                    for pass in 0..XPBD_PASSES.len() {
                        match exec {
                            None => xpbd_pass(&p, &topo.slots, pass, &mut x, &prev, &mut lambda),
                            Some(e) => xpbd_pass_rows(e, &p, &topo.slots, pass, &mut x, &prev, &mut lambda),
                        }
                    }
                }
                (x, lambda)
            };
            let want = run(None);
            assert!(want.0 != pos, "n = {n}: the passes moved nothing");
            for exec in [Exec::Serial, Exec::Parallel] {
                let got = run(Some(exec));
                let bits = |v: &[V4]| v.iter().flat_map(|x| x.map(f32::to_bits)).collect::<Vec<_>>();
                assert_eq!(bits(&got.0), bits(&want.0), "n = {n}, {exec:?}: positions");
                for b in 0..2 {
                    assert_eq!(bits(&got.1[b]), bits(&want.1[b]), "n = {n}, {exec:?}: λ in aux[{b}]");
                }
            }
        }
    }
}
