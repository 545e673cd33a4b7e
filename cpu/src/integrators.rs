//! The integrators other than Verlet (thesis §4.1.1–4.1.2), one function per GPU kernel.
//!
//! Every integrator keeps its state as positions and velocities (x, v), both f32: the
//! force kernels read `v`, so `forces`, `springs` and their fused and scattered forms
//! evaluate the force for every integrator unchanged; the integrators differ only in
//! where they evaluate it and how they combine the results. A velocity is never taken back
//! from a difference of two positions (which in f32 rounds `g·dt²` to a few ulps of x and
//! biased every integrator but Verlet by up to 7.5 % in free fall at 64 substeps), so each
//! integrator follows its own recurrence at any dt.
//!
//! Scratch state lives in [`AUX`] particle buffers (`aux`), whose meaning depends on the
//! integrator:
//!
//! | buffer | RK2, RK4 | implicit |
//! |---|---|---|
//! | `aux[0]` | `x₀` (w: pin flag) | `Δv`, the Newton step |
//! | `aux[1]` | `v₀` (damped) | `r` (w: the Jacobi preconditioner's diagonal) |
//! | `aux[2]` | `Σ bₛ vₛ` | `p` |
//! | `aux[3]` | `Σ bₛ aₛ·dt` | `q = A p` |
//! | `aux[4]` | the substep's wind force | — |
//!
//! XPBD keeps each spring's λ at the spring's first end: slots 1, 3, 7 in `aux[0]`'s x,
//! y, z and slots 6, 9, 11 in `aux[1]`'s (cleared at every substep's start); each
//! correction of a position adds its velocity (`Δx/dt`) at once.
//!
//! Pins, the grab and the floor end every integrator's substep as [`super::integrate`]
//! ends Verlet's (`finish_at`); spheres and boxes are the `collide` kernel's, run after.

use glam::Vec3;
use rayon::prelude::*;

use super::integrate::{floor_clamp, grab_vel};
use super::{Exec, v3, v4};
use clothlab_core::grid::{Rows, SpringSlot, V4};
use clothlab_core::step_params::StepParams;

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
pub(crate) fn per_particle<T: Send>(exec: Exec, count: usize, f: impl Fn(usize) -> T + Sync + Send) -> Vec<T> {
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
/// `v1`: the new `(pos, vel)` with the pins, the grab and the floor handled as
/// [`super::integrate`] handles them.
#[inline(always)]
pub(crate) fn finish_at(i: usize, p: &StepParams, x4: V4, x1: Vec3, v1: Vec3) -> (V4, V4) {
    if i as i32 == p.grab_index {
        let target = v3(p.grab_target);
        return (v4(target, x4[3]), v4(grab_vel(v3(x4), target, p.dt), 0.0));
    }
    if x4[3] == 0.0 {
        return (x4, [0.0; 4]);
    }
    let (xn, vn) = floor_clamp(p, x1, v1);
    (v4(xn, x4[3]), v4(vn, 0.0))
}

/// `f·dt/m`: a force as the velocity it adds in one substep to a particle whose position
/// has w = `w` (see `cpu::dt_over_mass`).
#[inline(always)]
fn accel_dt(p: &StepParams, f: V4, w: f32) -> Vec3 {
    v3(f) * super::dt_over_mass(p, w)
}

/// Explicit Euler: `x' = x + v·dt`, `v' = v + f·dt/m`, with `v` damped by
/// `(1 − damping)` first.
///
/// (Symplectic Euler, `v' = v + f·dt/m`, `x' = x + v'·dt`, needs no kernel of its own:
/// it is Verlet's recurrence in velocity form, step for step, so Verlet's kernels run it.)
pub fn euler(exec: Exec, p: &StepParams, force: &[V4], pos: &mut [V4], vel: &mut [V4]) {
    let out = per_particle(exec, pos.len(), |i| {
        let x = v3(pos[i]);
        let v0 = v3(vel[i]) * (1.0 - p.damping);
        let v1 = v0 + accel_dt(p, force[i], pos[i][3]);
        finish_at(i, p, pos[i], x + v0 * p.dt, v1)
    });
    for (i, (x, xp)) in out.into_iter().enumerate() {
        pos[i] = x;
        vel[i] = xp;
    }
}

/// The start of a Runge–Kutta substep: saves `x₀`, the damped `v₀` and the wind force
/// (which the force kernels add to), and writes `v₀` to the velocities so that the first
/// force evaluation sees the damped velocity.
pub fn rk_begin(exec: Exec, p: &StepParams, force: &[V4], pos: &[V4], vel: &mut [V4], aux: &mut [Vec<V4>]) {
    let out = per_particle(exec, pos.len(), |i| v4(v3(vel[i]) * (1.0 - p.damping), 0.0));
    for (i, v0) in out.into_iter().enumerate() {
        aux[0][i] = pos[i];
        aux[1][i] = v0;
        aux[4][i] = force[i];
        vel[i] = v0;
    }
}

/// One Runge–Kutta stage (see [`RkStage`]): adds the stage's `(v, a·dt)` to the weighted
/// sum, then either puts the particles at the next stage's point (the wind back in the
/// force buffer) or ends the substep at `y₀ + dt Σ bₛ kₛ`.
pub fn rk_stage(
    exec: Exec,
    p: &StepParams,
    st: &RkStage,
    force: &mut [V4],
    pos: &mut [V4],
    vel: &mut [V4],
    aux: &mut [Vec<V4>],
) {
    let out = per_particle(exec, pos.len(), |i| {
        let x4 = pos[i];
        let vs = v3(vel[i]);
        let gs = accel_dt(p, force[i], x4[3]);
        let (sx, su) =
            if st.first { (vs * st.b, gs * st.b) } else { (v3(aux[2][i]) + vs * st.b, v3(aux[3][i]) + gs * st.b) };
        let (x0, v0) = (v3(aux[0][i]), v3(aux[1][i]));
        let (x, xp) = if st.last {
            finish_at(i, p, x4, x0 + sx * p.dt, v0 + su)
        } else if held(i, p, x4) {
            (x4, [0.0; 4])
        } else {
            let x = x0 + vs * (st.c_next * p.dt);
            let v = v0 + gs * st.c_next;
            (v4(x, x4[3]), v4(v, 0.0))
        };
        (x, xp, v4(sx, 0.0), v4(su, 0.0))
    });
    for (i, (x, xp, sx, su)) in out.into_iter().enumerate() {
        pos[i] = x;
        vel[i] = xp;
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
    let (di, dj) = clothlab_core::grid::SLOT_OFFSETS[s];
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
/// λ starts at zero every substep), solved for both ends by their mobilities, in place;
/// each end's velocity gains its correction over dt (so that `v·dt` stays the particle's
/// displacement since the substep began, which the damping term reads).
pub fn xpbd_pass(
    p: &StepParams,
    slots: &Rows<SpringSlot>,
    pass: usize,
    pos: &mut [V4],
    vel: &mut [V4],
    lambda: &mut [Vec<V4>],
) {
    let (buf, c) = xpbd_lambda_home(pass);
    for a in 0..pos.len() {
        let Some((slot, b)) = pass_spring(p, slots, pass, a) else { continue };
        let l = lambda[buf][a][c];
        if let Some(s) = xpbd_solve(p, &slot, a, b, pos[a], pos[b], vel[a], vel[b], l) {
            (pos[a], pos[b], vel[a], vel[b]) = (s.xa, s.xb, s.va, s.vb);
            lambda[buf][a][c] = l + s.dl;
        }
    }
}

/// One XPBD pass of a mesh: springs `pass` of the list (a range of
/// [`clothlab_core::grid::MeshTables::xpbd_passes`], no two of which share a particle), each
/// solved as [`xpbd_pass`] solves a grid's, its λ in `lambda[k]` for spring `k`. The
/// pass's springs share no particle, so each is solved from the positions the pass
/// started with, in any order and on any thread (rayon with [`Exec::Parallel`]), and the
/// results are stored after: the same bits either way.
pub fn xpbd_mesh_pass(
    exec: Exec,
    p: &StepParams,
    springs: &[clothlab_core::grid::Spring],
    pass: std::ops::Range<usize>,
    pos: &mut [V4],
    vel: &mut [V4],
    lambda: &mut [f32],
) {
    let first = pass.start;
    let solved = {
        let (pos, vel, lambda) = (&*pos, &*vel, &*lambda);
        per_particle(exec, pass.len(), |i| {
            let k = first + i;
            let s = &springs[k];
            if s.ks <= 0.0 {
                return None;
            }
            let (a, b) = (s.a as usize, s.b as usize);
            let slot = SpringSlot { neighbor: s.b as i32, rest: s.rest, ks: s.ks, kd: s.kd };
            xpbd_solve(p, &slot, a, b, pos[a], pos[b], vel[a], vel[b], lambda[k])
        })
    };
    for (i, r) in solved.into_iter().enumerate() {
        let Some(r) = r else { continue };
        let (k, s) = (first + i, &springs[first + i]);
        let (a, b) = (s.a as usize, s.b as usize);
        (pos[a], pos[b], vel[a], vel[b]) = (r.xa, r.xb, r.va, r.vb);
        lambda[k] += r.dl;
    }
}

/// The spring pass `pass` solves at particle `a` (its first end), if any: the slot and
/// the other end.
#[inline(always)]
fn pass_spring(p: &StepParams, slots: &Rows<SpringSlot>, pass: usize, a: usize) -> Option<(SpringSlot, usize)> {
    let (s, colour) = XPBD_PASSES[pass];
    let n = p.n as usize;
    if xpbd_colour(s, (a % n) as u32, (a / n) as u32) != colour {
        return None;
    }
    let slot = slots.row(a)[s];
    (slot.neighbor >= 0 && slot.ks > 0.0).then_some((slot, slot.neighbor as usize))
}

/// [`xpbd_pass`] on rayon's threads, for a grid whose every spring points at its slot's
/// offset ([`clothlab_core::grid::ClothTopology::grid_slots`] is `Some`). The pass's springs share
/// no particle, so the order they are solved in changes no bit; they are solved in blocks
/// of rows that own both ends of their springs: a row each for the horizontal slots, and
/// for a slot reaching `dj` rows down, blocks of `2·dj` rows whose first `dj` rows hold the
/// springs' first ends, in two phases (the blocks starting at row 0, then at row `dj`).
pub fn xpbd_pass_rows(
    exec: Exec,
    p: &StepParams,
    slots: &Rows<SpringSlot>,
    pass: usize,
    pos: &mut [V4],
    vel: &mut [V4],
    lambda: &mut [Vec<V4>],
) {
    let (buf, c) = xpbd_lambda_home(pass);
    let n = p.n as usize;
    let dj = clothlab_core::grid::SLOT_OFFSETS[XPBD_PASSES[pass].0].1.unsigned_abs() as usize;
    let (block, firsts, phases) = if dj == 0 { (1, 1, 1) } else { (2 * dj, dj, 2) };
    for phase in 0..phases {
        let skip = phase * dj * n;
        let solve = |(k, ((xs, vs), ls)): RowBlock<'_>| {
            let start = skip + k * block * n;
            for r in 0..firsts.min(xs.len() / n) {
                for a in start + r * n..start + (r + 1) * n {
                    let Some((slot, b)) = pass_spring(p, slots, pass, a) else { continue };
                    let (la, lb) = (a - start, b - start);
                    let l = ls[la][c];
                    if let Some(s) = xpbd_solve(p, &slot, a, b, xs[la], xs[lb], vs[la], vs[lb], l) {
                        (xs[la], xs[lb], vs[la], vs[lb]) = (s.xa, s.xb, s.va, s.vb);
                        ls[la][c] = l + s.dl;
                    }
                }
            }
        };
        let (xs, vs, ls) = (&mut pos[skip..], &mut vel[skip..], &mut lambda[buf][skip..]);
        let rows = block * n;
        match exec {
            Exec::Serial => {
                xs.chunks_mut(rows).zip(vs.chunks_mut(rows)).zip(ls.chunks_mut(rows)).enumerate().for_each(solve)
            }
            Exec::Parallel => xs
                .par_chunks_mut(rows)
                .zip(vs.par_chunks_mut(rows))
                .zip(ls.par_chunks_mut(rows))
                .enumerate()
                .for_each(solve),
        }
    }
}

/// One solved XPBD constraint: both ends' new positions and velocities, and Δλ.
struct Solved {
    xa: V4,
    xb: V4,
    va: V4,
    vb: V4,
    dl: f32,
}

/// A block of rows of [`xpbd_pass_rows`]: its index, positions, velocities and λ.
type RowBlock<'a> = (usize, ((&'a mut [V4], &'a mut [V4]), &'a mut [V4]));

/// The constraint of `slot` between `a` (at `xa4`, moving at `va4`) and `b` with
/// multiplier `l`, or `None` when neither moves.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn xpbd_solve(
    p: &StepParams,
    slot: &SpringSlot,
    a: usize,
    b: usize,
    xa4: V4,
    xb4: V4,
    va4: V4,
    vb4: V4,
    l: f32,
) -> Option<Solved> {
    // w / m̄, one division: `w · (1 / m̄)` rounds twice, and a GPU compiler allowed to use
    // reciprocals turns it into the division (1 ulp apart where w ≠ 1, a mesh's masses).
    let (wa, wb) = (mobility(a, p, xa4) / p.particle_mass, mobility(b, p, xb4) / p.particle_mass);
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
    let rel = n.dot(v3(va4) - v3(vb4)) * p.dt;
    let dl = -((len - slot.rest) + alpha * l + gamma * rel) / ((1.0 + gamma) * (wa + wb) + alpha);
    let (da, db) = (n * (dl * wa), n * (dl * wb));
    let inv_dt = 1.0 / p.dt;
    Some(Solved {
        xa: v4(xa + da, xa4[3]),
        xb: v4(xb - db, xb4[3]),
        va: v4(v3(va4) + da * inv_dt, 0.0),
        vb: v4(v3(vb4) - db * inv_dt, 0.0),
        dl,
    })
}

// ---- implicit Euler: one Newton step, preconditioned conjugate gradients -------------
//
// In velocities the Newton step of backward Euler is `A Δv = dt f₀ − dt² K v₀`, `A = m(1 + dt·drag) I + Σₛ (dt² Kₛ + dt Dₛ)` over the springs,
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
    slots: &Rows<SpringSlot>,
    pos: &[V4],
    y: &dyn Fn(usize) -> Vec3,
    full: bool,
) -> (Vec3, f32) {
    let xa = v3(pos[i]);
    let ya = y(i);
    let m = super::mass(p, pos[i][3]) * (1.0 + p.dt * p.air_drag);
    let (mut acc, mut diag) = if full { (ya * m, m) } else { (Vec3::ZERO, m) };
    for s in slots.row(i) {
        let Some(b) = s.other() else { continue };
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
    terms.chunks(clothlab_core::layout::WORKGROUP as usize).map(|c| c.iter().sum()).collect()
}

/// The reduction kernels' fold of the partial sums.
pub fn fold(partials: &[f32]) -> f32 {
    partials.iter().sum()
}

/// Starts the solve from the force `f₀` in `force`: `Δv = 0`, `r = dt f₀ − dt² K v₀` (w:
/// the diagonal), `p = z = r/diag`; returns `r·z`.
pub fn cg_begin(
    exec: Exec,
    p: &StepParams,
    slots: &Rows<SpringSlot>,
    force: &[V4],
    pos: &[V4],
    vel: &[V4],
    aux: &mut [Vec<V4>],
) -> Vec<f32> {
    let u = |k: usize| v3(vel[k]);
    let out = per_particle(exec, pos.len(), |i| {
        let (ku, diag) = apply_at(i, p, slots, pos, &u, false);
        let r = if held(i, p, pos[i]) { Vec3::ZERO } else { v3(force[i]) * p.dt - ku };
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
pub fn cg_matvec(exec: Exec, p: &StepParams, slots: &Rows<SpringSlot>, pos: &[V4], aux: &mut [Vec<V4>]) -> Vec<f32> {
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

/// `Δv += α p`, `r −= α q`; returns the terms of the new `r·z`.
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

/// Ends the implicit substep: `v₁ = (1 − damping) v₀ + Δv`, `x₁ = x₀ + v₁·dt`.
pub fn implicit_finish(exec: Exec, p: &StepParams, pos: &mut [V4], vel: &mut [V4], aux: &[Vec<V4>]) {
    let out = per_particle(exec, pos.len(), |i| {
        let x = v3(pos[i]);
        let v1 = v3(vel[i]) * (1.0 - p.damping) + v3(aux[0][i]);
        finish_at(i, p, pos[i], x + v1 * p.dt, v1)
    });
    for (i, (x, xp)) in out.into_iter().enumerate() {
        pos[i] = x;
        vel[i] = xp;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clothlab_core::cloth::build;
    use clothlab_core::{Scene, SimParams};

    #[test]
    fn the_xpbd_passes_solve_every_spring_once_and_no_pass_touches_a_particle_twice() {
        // Grids with odd and even sides, and sides not a multiple of the bend springs' 4.
        for n in [5u32, 8, 13] {
            let (_, topo) = build(&Scene::with_n(n), &SimParams::default()).unwrap();
            let mut solved = 0;
            for &(s, colour) in &XPBD_PASSES {
                let mut touched = vec![false; topo.num_particles()];
                for a in 0..topo.num_particles() {
                    let slot = topo.slots.row(a)[s];
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
            let grab = clothlab_core::grid::Grab { particle: n + 1, target: [0.1, 2.0, 0.3] };
            let p = StepParams::new(&params, &Scene::with_n(n), Some(grab));
            let jitter = |k: usize, c: usize| ((k * 7919 + c * 104729) % 1000) as f32 * 1e-4;
            let pos: Vec<V4> = st
                .pos
                .iter()
                .enumerate()
                .map(|(k, x)| [x[0] * 1.3 + jitter(k, 0), x[1] + jitter(k, 1), x[2] * 1.2, x[3]])
                .collect();
            // Velocities of up to 6 cm/s, so that the damping term differs between springs.
            let vel: Vec<V4> = (0..pos.len()).map(|k| [jitter(k, 2) * 60.0, 0.0, -jitter(k, 1) * 60.0, 0.0]).collect();
            let run = |exec: Option<Exec>| {
                let (mut x, mut v, mut lambda) = (pos.clone(), vel.clone(), vec![vec![[0.0f32; 4]; pos.len()]; 2]);
                for _ in 0..2 {
                    for pass in 0..XPBD_PASSES.len() {
                        match exec {
                            None => xpbd_pass(&p, &topo.slots, pass, &mut x, &mut v, &mut lambda),
                            Some(e) => xpbd_pass_rows(e, &p, &topo.slots, pass, &mut x, &mut v, &mut lambda),
                        }
                    }
                }
                lambda.push(v);
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
                assert_eq!(bits(&got.1[2]), bits(&want.1[2]), "n = {n}, {exec:?}: velocities");
            }
        }
    }
}
