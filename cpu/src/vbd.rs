//! Vertex Block Descent (Chen, Liu, Yang & Yuksel, "Vertex Block Descent", ACM TOG 43(4),
//! 2024) for the mass-spring cloth: [`clothlab_core::Integrator::Vbd`]'s kernels, as the CPU
//! solvers run them and as the GPU kernels `vbd_begin`, `vbd_colour` and `vbd_finish`
//! compute them (their twins).
//!
//! A substep minimises implicit Euler's energy
//! `G(x) = Σᵢ mᵢ/(2h²) |xᵢ − yᵢ|² + Σ springs ½ k (|xᵢ − xⱼ| − r)²`, `yᵢ = xᵢ + h vᵢ + h² g`,
//! by sweeping the vertex colours ([`colouring`]: no two vertices of one colour share a
//! spring, so a colour's vertices are solved independently, in any order, each against
//! its neighbours' newest positions): each vertex takes one Newton step on its own
//! 3 × 3 block, `xᵢ ← xᵢ + Hᵢ⁻¹ fᵢ` with `fᵢ = −∂G/∂xᵢ` and
//! `Hᵢ = mᵢ/h² I + Σ k [n̂n̂ᵀ + max(0, 1 − r/l)(I − n̂n̂ᵀ)]` (the spring's Hessian made
//! positive semi-definite where it is compressed, as the paper does, so `Hᵢ` is positive
//! definite and the step always a descent). Spring damping is Rayleigh damping on each
//! spring's Hessian `Hₛ` (D = (kd/ks) Hₛ) acting on the two ends' relative displacement
//! this substep: `fᵢ −= (kd/(ks h)) Hₛ ((xᵢ − xᵢ⁰) − (xⱼ − xⱼ⁰))`, `Hᵢ += (kd/(ks h)) Hₛ`.
//! The paper damps each vertex's own displacement (`Hᵢ (xᵢ − xᵢ⁰)`), which damps a rigid
//! motion too: a free cloth thrown sideways lost 97 % of its momentum in 32 substeps with
//! it here; on the relative displacement a moving cloth keeps its momentum to what the
//! iterations leave (tests/vbd.rs).
//!
//! A substep: `forces` (gravity, drag and the wind, explicit, as for every integrator),
//! [`vbd_begin`] (the inertial prediction `y = x + h v'` with `v' = (1 − damping) v + h f/m`,
//! the integrate kernel's velocity), `iterations` × the colours' [`vbd_colour`] sweeps,
//! [`vbd_finish`] (`x = x⁰ + D`, `v = v' + (D − h v')/h`, the floor), then `collide`. The
//! colliders' contacts are penalty energies inside each vertex's solve, with smoothed
//! friction, as the paper has them (`contacts`); the `collide` after the solve puts back
//! outside what the penalties' reach left inside.
//!
//! The new velocity is the substep's displacement over h. D is kept as a sum of
//! small terms (`h v'` and each step) instead of being taken back as `x − x⁰`: in f32
//! that difference rounds `h² g` to a few ulps of x and biased every integrator of this
//! crate by up to 7.5 % in free fall before the state kept velocities (see
//! `integrators.rs`); with no spring stretched VBD is then exactly implicit Euler's
//! recurrence.

use glam::Vec3;
use rayon::prelude::*;

use super::collide::Colliders;
use super::integrators::{finish_at, per_particle};
use super::{Exec, dt_over_mass, mass, v3, v4};
use clothlab_core::contact::floor_contact;
use clothlab_core::grid::{ClothTopology, Colours, Rows, SpringSlot, V4};
use clothlab_core::step_params::StepParams;

/// A contact's penalty stiffness as a multiple of the vertex's inertia `m/h²` (so the
/// same at every n and dt): a cloth resting on a surface sinks `g h² / 1000` into the
/// penalty's reach (1e-9 m at 960 substeps per second).
pub const CONTACT_STIFFNESS: f32 = 1000.0;
/// How far beyond the collision margin a contact's penalty starts, as a fraction of the
/// margin: the cloth rests that far out, so that `collide`'s projection after the solve
/// (kept as the fallback for what the sweeps leave inside the margin) does not act on a
/// resting contact and its velocity friction is not applied twice.
pub const CONTACT_REACH: f32 = 0.1;
/// The friction's smoothing speed (the paper's and IPC's ε_v), m/s: below it the friction
/// force grows linearly with the sliding speed, so that its Hessian stays bounded.
pub const FRICTION_EPS_V: f32 = 0.01;

/// The vertex colours of `topo`: lists of particles, no two of one list joined by a spring.
/// A grid: the 9 classes of `(i mod 3, j mod 3)` (its 12-slot stencil reaches 2 away, so
/// two particles of one class, 3 apart or more, share none). A mesh: greedy over its rows
/// in particle order (each particle the smallest colour none of its springs' other ends
/// has), as many colours as that takes (a fan's centre of valence 64 apart, a few more
/// than the largest row of a mesh's lattice).
pub fn colouring(topo: &ClothTopology) -> Vec<Vec<u32>> {
    if topo.mesh.is_none() {
        return Colours::grid(topo.n as usize);
    }
    Colours::greedy(topo.num_particles(), |i| topo.slots.row(i).iter().filter_map(|s| s.other()).collect::<Vec<_>>())
}

/// Whether `colours` holds every particle of `topo` once and no colour two particles
/// joined by a spring.
pub fn colouring_is_valid(topo: &ClothTopology, colours: &[Vec<u32>]) -> bool {
    let np = topo.num_particles();
    let mut colour_of = vec![usize::MAX; np];
    for (c, list) in colours.iter().enumerate() {
        for &k in list {
            match colour_of.get_mut(k as usize) {
                Some(slot) if *slot == usize::MAX => *slot = c,
                _ => return false,
            }
        }
    }
    colour_of.iter().all(|&c| c != usize::MAX)
        && (0..np).all(|i| topo.slots.row(i).iter().filter_map(|s| s.other()).all(|j| colour_of[j] != colour_of[i]))
}

/// The scratch buffers a VBD substep keeps (`aux[0]`, `aux[1]`, `aux[2]`, as the GPU keeps
/// them in aux0 … aux2): the predicted velocity v' (w: 0; the prediction `y = x⁰ + h v'`),
/// the substep's start x⁰, and the displacement D so far (w: 0). The solve works on
/// displacements only — the inertia's `y − x` as `h v' − D`, a spring's `xᵢ − xⱼ` as
/// `(x⁰ᵢ − x⁰ⱼ) + (Dᵢ − Dⱼ)`, the damping's relative motion as `Dᵢ − Dⱼ` — and the
/// positions are `x⁰ + D` once, at the finish. A spring then sees its ends to a few ulps
/// of its length, not of the positions: where the solve read positions `x⁰ + D` rounded
/// (ulp 2.4e-7 m at 3.7 m) it answered that rounding with steps of its size, which over h
/// are velocities (7 mm/s at 512 substeps), and a free cloth fell 2e-4 too far in 0.25 s;
/// where it stepped the positions themselves, over 40 iterations, it lost 3.7e-3 of a
/// free cloth's momentum in 32 substeps.
/// The new velocity is `v' + (D − h v')/h`: what the solve changed, over h, added to the
/// prediction's velocity (as `D/h` it rounded `h v'` and `1/h` into every velocity, and a
/// free cloth's mean velocity lost 2.7e-6 of itself in 240 substeps whatever the
/// iterations).
pub const VBD_AUX: usize = 3;

/// The start of a VBD substep, per particle: the prediction `y = x + D` with
/// `D = h v'`, `v' = (1 − damping) v + f h/m` (`f` the force buffer after `forces`). A
/// pinned particle predicts its place (D = 0), the grabbed one the grab's target.
/// `aux[0]` = v' (zero for a held particle), `aux[1]` = x⁰, `aux[2]` = D = y − x⁰; the
/// positions stay x⁰ until [`vbd_finish`].
pub fn vbd_begin(exec: Exec, p: &StepParams, force: &[V4], pos: &[V4], vel: &[V4], aux: &mut [Vec<V4>]) {
    let out = per_particle(exec, pos.len(), |i| begin_at(i, p, force[i], pos[i], vel[i]));
    for (i, (d, v)) in out.into_iter().enumerate() {
        aux[0][i] = v4(v, 0.0);
        aux[1][i] = pos[i];
        aux[2][i] = v4(d, 0.0);
    }
}

/// Particle `i`'s displacement and predicted velocity (see [`vbd_begin`]).
#[inline(always)]
fn begin_at(i: usize, p: &StepParams, force: V4, x4: V4, vel: V4) -> (Vec3, Vec3) {
    if i as i32 == p.grab_index {
        (v3(p.grab_target) - v3(x4), Vec3::ZERO)
    } else if x4[3] == 0.0 {
        (Vec3::ZERO, Vec3::ZERO)
    } else {
        let v = v3(vel) * (1.0 - p.damping) + v3(force) * dt_over_mass(p, x4[3]);
        (v * p.dt, v)
    }
}

/// The contact between triangles inside VBD's solves (`vbd_colour_tri`): each particle's
/// contact terms for the colour being swept (`crate::tri_pipeline::Contact::vbd_terms`, or
/// the `tri_vbd` kernel's twin; [`clothlab_core::tri_contact::VBD_TERMS`] words a particle), which
/// the sweep adds to its block and clears, and the positions, which it keeps at the
/// iterate `x⁰ + D` for the next colour's terms.
pub struct TriVbd<'a> {
    /// The terms.
    pub sums: &'a mut [u32],
    /// The positions.
    pub pos: &'a mut [V4],
}

/// One colour's sweep: every particle of `colour` (no two of which share a spring) takes
/// its Newton step on its own block against its neighbours' newest displacements and adds
/// it to its displacement `aux[2]`. Pinned and grabbed particles stay. With `tri` (the
/// contact between triangles) each block takes its contact terms too.
pub fn vbd_colour(
    exec: Exec,
    p: &StepParams,
    slots: &Rows<SpringSlot>,
    colliders: Colliders<'_>,
    colour: &[u32],
    aux: &mut [Vec<V4>],
    mut tri: Option<TriVbd<'_>>,
) {
    let (pred, start, disp) = (&aux[0], &aux[1], &aux[2]);
    let colliders = colliders.cut(p);
    let sums = tri.as_ref().map(|t| &*t.sums);
    let step = |&i: &u32| block_step(p, slots, colliders, i as usize, pred, start, disp, sums);
    let steps: Vec<Vec3> = match exec {
        Exec::Serial => colour.iter().map(step).collect(),
        Exec::Parallel => colour.par_iter().with_min_len(128).map(step).collect(),
    };
    for (&i, s) in colour.iter().zip(steps) {
        let i = i as usize;
        aux[2][i] = v4(v3(aux[2][i]) + s, 0.0);
        if let Some(t) = &mut tri {
            t.sums[clothlab_core::tri_contact::VBD_TERMS * i..][..clothlab_core::tri_contact::VBD_TERMS].fill(0);
            t.pos[i] = iterate_at(&aux[1][i], &aux[2][i]);
        }
    }
}

/// The iterate `x⁰ + D` of a particle with start `x4` (its w kept) and displacement `d`.
#[inline(always)]
fn iterate_at(x4: &V4, d: &V4) -> V4 {
    v4(v3(*x4) + v3(*d), x4[3])
}

/// The positions at the iterate, `x⁰ + D` (`vbd_positions`): what the contact between
/// triangles' terms are found at (after the prediction and each Chebyshev step; each
/// colour's sweep keeps its own particles').
pub fn vbd_positions(exec: Exec, pos: &mut [V4], aux: &[Vec<V4>]) {
    super::for_each(exec, pos, |i, x| *x = iterate_at(&aux[1][i], &aux[2][i]));
}

/// The end of a VBD substep: `x = x⁰ + D`, `v = v' + (D − h v')/h`, the floor's contact,
/// pins and the grab as every integrator ends (`integrators::finish_at`).
pub fn vbd_finish(exec: Exec, p: &StepParams, pos: &mut [V4], vel: &mut [V4], aux: &[Vec<V4>]) {
    let out = per_particle(exec, pos.len(), |i| {
        let (d, v) = (v3(aux[2][i]), v3(aux[0][i]));
        finish_at(i, p, aux[1][i], v3(aux[1][i]) + d, v + (d - v * p.dt) * (1.0 / p.dt))
    });
    for (i, (x, v)) in out.into_iter().enumerate() {
        pos[i] = x;
        vel[i] = v;
    }
}

/// The paper's Chebyshev weight after sweep `k` (from 1) for the spectral radius `rho`:
/// `ω₁ = 1`, `ω₂ = 2/(2 − ρ²)`, `ω_k = 4/(4 − ρ² ω_{k−1})`.
pub fn chebyshev_omega(k: u32, rho: f32) -> f32 {
    let mut omega = 1.0f32;
    for j in 2..=k {
        omega = if j == 2 { 2.0 / (2.0 - rho * rho) } else { 4.0 / (4.0 - rho * rho * omega) };
    }
    omega
}

/// The paper's Chebyshev acceleration after a sweep with weight `omega`
/// ([`chebyshev_omega`]), per free particle: `D ← ω (D − D⁽ᵏ⁻²⁾) + D⁽ᵏ⁻²⁾`, the sweeps'
/// last two results kept in `aux[3]` (the last) and `aux[4]` (the one before). After the
/// first sweep (`omega` = 1) D is kept as it is and the two are set up: the one before is
/// the prediction's `h v'`. Pinned and grabbed particles keep their D.
pub fn vbd_accelerate(exec: Exec, p: &StepParams, omega: f32, aux: &mut [Vec<V4>]) {
    let out = per_particle(exec, aux[2].len(), |i| {
        let d = v3(aux[2][i]);
        let x4 = aux[1][i];
        if i as i32 == p.grab_index || x4[3] == 0.0 {
            return (d, d, d);
        }
        if omega == 1.0 {
            return (d, d, v3(aux[0][i]) * p.dt);
        }
        let (last, before) = (v3(aux[3][i]), v3(aux[4][i]));
        let acc = (d - before) * omega + before;
        (acc, acc, last)
    });
    for (i, (d, last, before)) in out.into_iter().enumerate() {
        aux[2][i] = v4(d, 0.0);
        aux[3][i] = v4(last, 0.0);
        aux[4][i] = v4(before, 0.0);
    }
}

/// One VBD substep of `iterations` sweeps over `colours` ([`colouring`]), `pos` and `vel`
/// in place, with gravity and drag as the only external forces (no wind) and the floor of
/// `p` the only collider: what the solvers run between `forces` and `collide`, for the
/// tests.
pub fn vbd_substep(
    p: &StepParams,
    topo: &ClothTopology,
    colours: &[Vec<u32>],
    iterations: u32,
    pos: &mut [V4],
    vel: &mut [V4],
) {
    let e = Exec::Serial;
    let mut force = vec![[0.0; 4]; pos.len()];
    super::forces(e, p, pos, vel, &mut force);
    let mut aux = vec![vec![[0.0; 4]; pos.len()]; VBD_AUX];
    vbd_begin(e, p, &force, pos, vel, &mut aux);
    for _ in 0..iterations {
        for colour in colours {
            vbd_colour(e, p, &topo.slots, Colliders::default(), colour, &mut aux, None);
        }
    }
    vbd_finish(e, p, pos, vel, &aux);
}

/// Particle `i`'s Newton step on its block: `Hᵢ⁻¹ fᵢ` at `x⁰ + D` (the others' newest
/// displacements), `pred` the predicted velocities v' (`y − x⁰ = h v'`), `start` x⁰,
/// `disp` the displacements D; zero for a
/// held particle and where the
/// block cannot be solved (its determinant not positive and finite in f32). Written
/// scalar by scalar in the order `vbd_colour.wgsl` computes it: the block's six entries
/// summed slot by slot, then the contact between triangles' terms (`tri`, see [`TriVbd`]),
/// then the colliders' contacts (penalties and friction, `contacts`), solved by cofactors.
#[allow(clippy::too_many_arguments)]
pub fn block_step(
    p: &StepParams,
    slots: &Rows<SpringSlot>,
    colliders: Colliders<'_>,
    i: usize,
    pred: &[V4],
    start: &[V4],
    disp: &[V4],
    tri: Option<&[u32]>,
) -> Vec3 {
    let x4 = start[i];
    if i as i32 == p.grab_index || x4[3] == 0.0 {
        return Vec3::ZERO;
    }
    let h = p.dt;
    let x0 = v3(x4);
    let inertia = mass(p, x4[3]) / (h * h);
    let moved = v3(disp[i]);
    let mut f = (v3(pred[i]) * h - moved) * inertia;
    // The block's six entries: h00 h11 h22 h01 h02 h12.
    let mut hess = [inertia, inertia, inertia, 0.0, 0.0, 0.0];
    for s in slots.row(i) {
        let Some(j) = s.other() else { continue };
        if s.ks <= 0.0 {
            continue;
        }
        // Both ends relative to where they started (an exact difference for neighbours
        // in one binade), plus their displacements.
        let u = moved - v3(disp[j]);
        let dx = (x0 - v3(start[j])) + u;
        let l = dx.dot(dx).sqrt();
        if l <= f32::MIN_POSITIVE {
            continue;
        }
        let n = dx * (1.0 / l);
        // Hₛ = a I + b n̂n̂ᵀ: ks along the spring, ks·max(0, 1 − r/l) across it (zero
        // where it is compressed: positive semi-definite).
        let a = s.ks * (1.0 - s.rest / l).max(0.0);
        let b = s.ks - a;
        f -= n * (s.ks * (l - s.rest));
        let mut scale = 1.0;
        if s.kd > 0.0 {
            // Rayleigh damping D = (kd/ks) Hₛ on the ends' relative displacement over h.
            let c = s.kd / (s.ks * h);
            let hu = u * a + n * (b * n.dot(u));
            f -= hu * c;
            scale = 1.0 + c;
        }
        add_block(&mut hess, a * scale, b * scale, n);
    }
    if let Some(sums) = tri {
        tri_terms(
            p,
            &sums[clothlab_core::tri_contact::VBD_TERMS * i..][..clothlab_core::tri_contact::VBD_TERMS],
            &mut f,
            &mut hess,
        );
    }
    contacts(p, colliders, inertia * CONTACT_STIFFNESS, x0 + moved, moved, &mut f, &mut hess);
    solve_sym3(hess, f)
}

/// A particle's contact terms between triangles (`crate::tri_pair::vbd_terms`'s
/// fixed-point sums) added to its force and block, times the contact's stiffness
/// `k` = [`CONTACT_STIFFNESS`] × the reference particle's inertia m̄/h² (one stiffness for
/// every pair, so that the terms are one energy's): the force in units of
/// `k t / CONTACT_UNITS`, the block in `k / CONTACT_UNITS`.
#[inline(always)]
fn tri_terms(p: &StepParams, s: &[u32], f: &mut Vec3, h: &mut [f32; 6]) {
    let k = p.particle_mass / (p.dt * p.dt) * CONTACT_STIFFNESS;
    let fu = k * (p.self_thickness * (1.0 / clothlab_core::tables::CONTACT_UNITS));
    let hu = k * (1.0 / clothlab_core::tables::CONTACT_UNITS);
    let at = |w: usize| s[w] as i32 as f32;
    *f += Vec3::new(at(0), at(1), at(2)) * fu;
    for (c, e) in h.iter_mut().enumerate() {
        *e += at(3 + c) * hu;
    }
}

/// Adds `a I + b n̂n̂ᵀ` to the block `[h00, h11, h22, h01, h02, h12]`.
#[inline(always)]
fn add_block(h: &mut [f32; 6], a: f32, b: f32, n: Vec3) {
    h[0] += a + b * n.x * n.x;
    h[1] += a + b * n.y * n.y;
    h[2] += a + b * n.z * n.z;
    h[3] += b * n.x * n.y;
    h[4] += b * n.x * n.z;
    h[5] += b * n.y * n.z;
}

/// The contacts of a vertex at `x` that moved `d` this substep, as penalty energies in its
/// block (the paper's §3.5): within the collision margin plus [`CONTACT_REACH`] of it of
/// the floor, a sphere or a box (the box's nearest face), penetration `δ` along the
/// surface's normal n̂, the energy `½ k δ²` (`k` = `stiffness`) adds `k δ n̂` to the force
/// and `k n̂n̂ᵀ` to the block. Friction is the paper's (IPC's smoothed Coulomb friction,
/// μ = `friction`, or `kinetic_friction` with Coulomb's coefficients, `StepParams::vbd_mu`, on the tangential displacement `u` over the substep of a still
/// collider): `−μ λ f₁(|u|)/|u| u` with `f₁(y)/y = 2/ε − y/ε²` below
/// `ε = FRICTION_EPS_V · h` and `1/y` above, its Hessian `μ λ f₁(|u|)/|u| (I − n̂n̂ᵀ)`.
/// The normal force λ is lagged as the paper lags it, but to the block's own Newton step
/// rather than the last iteration: `λ = k max(0, δ − n̂·f / n̂ᵀHn̂)` with f and H after the
/// penalties, the contact's force once this step is taken. With `λ = k δ` at the
/// iterate, the first sweep of a substep saw the prediction's whole depth (λ a thousand
/// times the weight), cut the sliding nearly to nothing, and 8 sweeps did not win it
/// back: a cloth sliding on the floor slowed 10 % faster than Coulomb's μg.
#[inline(always)]
fn contacts(
    p: &StepParams,
    colliders: Colliders<'_>,
    stiffness: f32,
    x: Vec3,
    d: Vec3,
    f: &mut Vec3,
    h: &mut [f32; 6],
) {
    each_contact(p, colliders, x, |pen, n, _| {
        *f += n * (stiffness * pen);
        add_block(h, 0.0, stiffness, n);
    });
    let mu = p.vbd_mu();
    if mu <= 0.0 {
        return;
    }
    let (fa, ha) = (*f, *h);
    let eps = FRICTION_EPS_V * p.dt;
    each_contact(p, colliders, x, |pen, n, vs| {
        // n̂ᵀHn̂ of the block so far (positive: the inertia alone is).
        let hn = n.x * (ha[0] * n.x + ha[3] * n.y + ha[4] * n.z)
            + n.y * (ha[3] * n.x + ha[1] * n.y + ha[5] * n.z)
            + n.z * (ha[4] * n.x + ha[5] * n.y + ha[2] * n.z);
        let lambda = stiffness * (pen - n.dot(fa) / hn).max(0.0);
        // The displacement relative to the surface (a moving collider's moved vs·h).
        let dr = d - vs * p.dt;
        let u = dr - n * n.dot(dr);
        let y = u.dot(u).sqrt();
        let c = if y < eps { 2.0 / eps - y / (eps * eps) } else { 1.0 / y };
        let w = mu * lambda * c;
        *f -= u * w;
        add_block(h, w, -w, n);
    });
}

/// Calls `touch(δ, n̂, v_s)` for every contact of a vertex at `x` (see [`contacts`]): the
/// floor, then every collider in scene order ([`Colliders::walk`]), each grown by the
/// margin and its reach; `v_s` the surface's velocity at the contact's point
/// (`clothlab_core::motion`; zero for a still collider).
#[inline(always)]
fn each_contact(p: &StepParams, colliders: Colliders<'_>, x: Vec3, mut touch: impl FnMut(f32, Vec3, Vec3)) {
    let reach = p.margin + p.margin * CONTACT_REACH;
    if let Some(c) = floor_contact(p.floor_y, x, reach) {
        touch(c.depth, c.n, c.vs);
    }
    colliders.walk(&mut x.clone(), reach, |_, c| touch(c.depth, c.n, c.vs));
}

/// `H⁻¹ f` for the symmetric `H` given as `[h00, h11, h22, h01, h02, h12]`, by cofactors;
/// zero unless the determinant is positive and finite.
#[inline(always)]
fn solve_sym3(h: [f32; 6], f: Vec3) -> Vec3 {
    let [a, d, e, b, c, g] = h;
    // H = [a b c; b d g; c g e]
    let c00 = d * e - g * g;
    let c01 = c * g - b * e;
    let c02 = b * g - c * d;
    let det = a * c00 + b * c01 + c * c02;
    if !(det > 0.0 && det <= f32::MAX) {
        return Vec3::ZERO;
    }
    let c11 = a * e - c * c;
    let c12 = b * c - a * g;
    let c22 = a * d - b * b;
    let r = 1.0 / det;
    Vec3::new(
        (c00 * f.x + c01 * f.y + c02 * f.z) * r,
        (c01 * f.x + c11 * f.y + c12 * f.z) * r,
        (c02 * f.x + c12 * f.y + c22 * f.z) * r,
    )
}
