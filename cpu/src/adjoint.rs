//! The adjoint kernels' twins (docs/gradients.md, "The GPU route"): a substep's adjoint in
//! f32 on the adjoint's planes ([`clothlab_core::layout::Buf::Adjoint`]), per particle as
//! `adj_integrate.wgsl` and `adj_springs.wgsl` compute it. Run after the substep's force
//! is recomputed at its input (`forces`, `springs`: the force buffer holds the total
//! force), `adj_integrate` then `adj_springs` take the gradient with respect to the
//! substep's output (planes 0 and 1) to the one with respect to its input, and add each
//! particle's partials of the parameters to planes 3 … 7 ([`Partial`]); the sum over the
//! particles is the parameters' gradient, summed by the caller once a backward pass.
//! [`crate::grad::Model::adjoint`] is the f64 reference they are checked against.

use glam::Vec3;

use super::{Exec, dt_over_mass, for_each, mass, v3, v4};
use crate::collide::Colliders;
use crate::integrate::contact_vel;
use clothlab_core::grid::{Rows, SpringSlot, TETHER_SLOTS, Tether, V4};
use clothlab_core::layout::ADJ_ROWS;
use clothlab_core::layout::STRAIN_AIM;
use clothlab_core::step_params::StepParams;

/// The partials' places: plane and component of each.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Partial {
    /// Gravity's component `c` (plane 3, x y z).
    Gravity(usize),
    /// The air drag (plane 3, w).
    AirDrag,
    /// The velocity damping (plane 4, x).
    Damping,
    /// The share friction (plane 4, y).
    Friction,
    /// The particle mass `StepParams::particle_mass` (plane 4, z).
    ParticleMass,
    /// The strain limit τ (plane 4, w).
    StrainLimit,
    /// A spring family's (0 structural or a mesh's edges, 1 shear, 2 bend): `Σ ∂/∂ks`,
    /// `Σ ∂/∂kd`, `Σ ks ∂/∂ks`, `Σ kd ∂/∂kd` over its springs (planes 5, 6, 7, x y z w).
    Spring(usize, usize),
}

impl Partial {
    /// Its plane and component.
    pub fn at(self) -> (usize, usize) {
        match self {
            Partial::Gravity(c) => (3, c),
            Partial::AirDrag => (3, 3),
            Partial::Damping => (4, 0),
            Partial::Friction => (4, 1),
            Partial::ParticleMass => (4, 2),
            Partial::StrainLimit => (4, 3),
            Partial::Spring(kind, c) => (5 + kind, c),
        }
    }
}

/// The partials' sums a backward pass ends with: planes 3 … 7 summed over the
/// particles in f64, four a plane ([`partial_sums`]; [`Partial::at`]'s plane − 3, times
/// 4, plus its component).
pub const PARTIALS: usize = 4 * 5;

/// Every partial's sum over the `np` particles of `adjoint` ([`PARTIALS`]).
pub fn partial_sums(adjoint: &[V4], np: usize) -> [f64; PARTIALS] {
    let mut s = [0.0; PARTIALS];
    for (k, sum) in s.iter_mut().enumerate() {
        let plane = 3 + k / 4;
        *sum = adjoint[plane * np..(plane + 1) * np].iter().map(|v| v[k % 4] as f64).sum();
    }
    s
}

/// The planes of `np` particles as ([`ADJ_ROWS`] slices).
fn planes(adjoint: &mut [V4], np: usize) -> Vec<&mut [V4]> {
    assert_eq!(adjoint.len(), ADJ_ROWS as usize * np, "the adjoint's planes of {np} particles");
    adjoint.chunks_mut(np).collect()
}

/// What [`slide_back`] gives: the gradients with respect to a contact's velocity, its
/// normal and the friction.
struct Slid {
    g_v: Vec3,
    g_n: Vec3,
    g_f: f32,
}

/// [`contact_vel`] taken back onto `gv`.
fn slide_back(p: &StepParams, v: Vec3, n: Vec3, gv: Vec3) -> Slid {
    let vn = v.dot(n);
    let keep = 1.0 - p.friction;
    let on = if vn > 0.0 { 1.0 } else { 0.0 };
    let gvn = n.dot(gv);
    let g_v = (gv - gvn * n) * keep + (on * gvn) * n;
    let g_n = (on - keep) * (vn * gv + gvn * v);
    Slid { g_v, g_n, g_f: -(v - vn * n).dot(gv) }
}

/// A sphere's contact as `sphere_contact` finds it: the unit normal, the distance from
/// the centre and the grown radius, or nothing.
fn sphere_hit(s: &clothlab_core::scene::Sphere, margin: f32, x: Vec3) -> Option<(Vec3, f32, f32)> {
    let r = s.radius + margin;
    let d = x - Vec3::from(s.center);
    let dist2 = d.dot(d);
    if dist2 >= r * r {
        return None;
    }
    let dist = dist2.sqrt();
    let n = if dist > 1e-12 { d / dist } else { Vec3::Y };
    Some((n, dist, r))
}

/// `adj_integrate`'s twin: per particle, the adjoint of `integrate` (Verlet in velocity
/// form, the floor) and `collide`'s still spheres at the substep's input `pos`, `vel`
/// with the total force `force`.
pub fn adj_integrate(
    exec: Exec,
    p: &StepParams,
    c: Colliders<'_>,
    pos: &[V4],
    vel: &[V4],
    force: &[V4],
    adjoint: &mut [V4],
) {
    let np = pos.len();
    let mut out = vec![[[0.0f32; 4]; 5]; np];
    let planes = planes(adjoint, np);
    let (xb, vb, p3, p4) = (&*planes[0], &*planes[1], &*planes[3], &*planes[4]);
    let spheres = &c.spheres[..(p.num_spheres as usize).min(c.spheres.len())];
    for_each(exec, &mut out, |i, o| {
        let w = pos[i][3];
        if w == 0.0 {
            *o = [xb[i], [0.0; 4], [0.0; 4], p3[i], p4[i]];
            return;
        }
        let (x, v, f) = (v3(pos[i]), v3(vel[i]), v3(force[i]));
        let k = dt_over_mass(p, w);
        let vt = v * (1.0 - p.damping) + f * k;
        let xt = x + vt * p.dt;
        let floor = p.floor_y + p.margin;
        let floored = xt.y < floor;
        let (mut xc, mut vc) = (xt, vt);
        if floored {
            xc.y = floor;
            vc = contact_vel(vt, Vec3::Y, p.friction);
        }
        let (mut gx, mut gv) = (v3(xb[i]), v3(vb[i]));
        let mut g_friction = 0.0;
        for s in (1..=spheres.len()).rev() {
            let (mut xs, mut vs) = (xc, vc);
            for q in &spheres[..s - 1] {
                if let Some((n, _, r)) = sphere_hit(q, p.margin, xs) {
                    vs = contact_vel(vs, n, p.friction);
                    xs = Vec3::from(q.center) + n * r;
                }
            }
            let Some((n, dist, r)) = sphere_hit(&spheres[s - 1], p.margin, xs) else { continue };
            let b = slide_back(p, vs, n, gv);
            g_friction += b.g_f;
            let gn = b.g_n + gx * r;
            gx = (gn - n.dot(gn) * n) / dist.max(1e-12);
            gv = b.g_v;
        }
        if floored {
            gx.y = 0.0;
            let b = slide_back(p, vt, Vec3::Y, gv);
            g_friction += b.g_f;
            gv = b.g_v;
        }
        let gvt = gv + gx * p.dt;
        let g_f = gvt * k;
        let m = mass(p, w);
        let g = v3(p.gravity);
        let g_mass = -gvt.dot(f) * k / p.particle_mass + g_f.dot(g - p.air_drag * v) / w.max(1e-30);
        let add = |a: V4, b: V4| [a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3]];
        *o = [
            v4(gx, 0.0),
            v4(gvt * (1.0 - p.damping) - g_f * (p.air_drag * m), 0.0),
            v4(g_f, 0.0),
            add(p3[i], v4(g_f * m, -g_f.dot(v) * m)),
            add(p4[i], [-v.dot(gvt), g_friction, g_mass, 0.0]),
        ];
    });
    let mut planes = planes;
    for (i, o) in out.iter().enumerate() {
        for (r, v) in o.iter().enumerate() {
            planes[r][i] = *v;
        }
    }
}

/// `adj_springs`' twin: per particle, each spring of its row taken back onto this end
/// (`Jᵀ (ḡ_a − ḡ_b)` onto its position's and velocity's gradients, ḡ the force's from
/// plane 2), each spring's partials counted at its lower end by family (`grid`: a grid's
/// slots, four a family; else a mesh's: its row's head the edges, the rest bending).
pub fn adj_springs(exec: Exec, grid: bool, slots: &Rows<SpringSlot>, pos: &[V4], vel: &[V4], adjoint: &mut [V4]) {
    let np = pos.len();
    let mut out = vec![[[0.0f32; 4]; 5]; np];
    let planes = planes(adjoint, np);
    let gf = &*planes[2];
    for_each(exec, &mut out, |i, o| {
        let (xa, va, ga) = (v3(pos[i]), v3(vel[i]), v3(gf[i]));
        let (mut gx, mut gv) = (Vec3::ZERO, Vec3::ZERO);
        let mut part = [[0.0f32; 4]; 3];
        let head = slots.head(i).len();
        for (s, slot) in slots.row(i).iter().enumerate() {
            let Some(b) = slot.other() else { continue };
            let l = xa - v3(pos[b]);
            let len = l.dot(l).sqrt();
            if len <= f32::MIN_POSITIVE {
                continue;
            }
            let dir = l * (1.0 / len);
            let dv = va - v3(vel[b]);
            let fb = ga - v3(gf[b]);
            let stretch = len - slot.rest;
            let rate = dv.dot(dir);
            let sc = slot.ks * stretch + slot.kd * rate;
            let along = dir.dot(fb);
            gx += -along * (slot.ks * dir + slot.kd * (dv - rate * dir) / len) - (sc / len) * (fb - along * dir);
            gv += (-slot.kd * along) * dir;
            if i < b {
                let kind = if grid {
                    s / 4
                } else if s < head {
                    0
                } else {
                    2
                };
                let (gks, gkd) = (-stretch * along, -rate * along);
                let q = &mut part[kind];
                for (c, d) in [gks, gkd, gks * slot.ks, gkd * slot.kd].into_iter().enumerate() {
                    q[c] += d;
                }
            }
        }
        *o = [v4(gx, 0.0), v4(gv, 0.0), part[0], part[1], part[2]];
    });
    let mut planes = planes;
    for (i, o) in out.iter().enumerate() {
        for (r, plane) in [0, 1, 5, 6, 7].into_iter().enumerate() {
            let a = &mut planes[plane][i];
            for c in 0..4 {
                a[c] += o[r][c];
            }
        }
    }
}

/// `adj_strain_back`'s twin: per particle, at a strain pass's input `pos` with its
/// `counts`, the gradient with respect to the pass's output point `ȳ = x̄′ + v̄′/dt`
/// taken back through the tethers to the point before them (plane 2), each tether's
/// share of its pin (planes 8, 9: the share, the pin's index in w, −1 none) and the
/// strain limit's partial added to plane 4's w.
pub fn adj_strain_back(
    exec: Exec,
    p: &StepParams,
    slots: &Rows<SpringSlot>,
    tethers: &[[Tether; TETHER_SLOTS]],
    pos: &[V4],
    counts: &[V4],
    adjoint: &mut [V4],
) {
    let np = pos.len();
    let mut out = vec![[[0.0f32; 4]; 4]; np];
    let planes = planes(adjoint, np);
    let (xb, vb, p4) = (&*planes[0], &*planes[1], &*planes[4]);
    let stretch = 1.0 + p.strain_limit;
    let aim = 1.0 + STRAIN_AIM * p.strain_limit;
    for_each(exec, &mut out, |i, o| {
        let mut g = v3(xb[i]) + v3(vb[i]) * (1.0 / p.dt);
        let none = [0.0, 0.0, 0.0, -1.0];
        let wi = pos[i][3];
        if wi == 0.0 {
            *o = [v4(g, 0.0), none, none, p4[i]];
            return;
        }
        let xi = v3(pos[i]);
        let ci = counts[i][0];
        let (mut corr, mut count) = (Vec3::ZERO, 0.0f32);
        if ci > 0.0 {
            for slot in slots.head(i) {
                if slot.neighbor < 0 {
                    continue;
                }
                let b = slot.neighbor as usize;
                let d = v3(pos[b]) - xi;
                let len = d.dot(d).sqrt();
                if len > stretch * slot.rest {
                    let wb = pos[b][3];
                    corr += d * (wi * (len - aim * slot.rest) / ((wi + wb) * len * ci.max(counts[b][0]).max(1.0)));
                    count += 1.0;
                }
            }
        }
        let mut z = if count > 0.0 { xi + corr } else { xi };
        let mut before = [Vec3::ZERO; TETHER_SLOTS];
        let mut on = [false; TETHER_SLOTS];
        for (t, tether) in tethers[i].iter().enumerate() {
            before[t] = z;
            if tether.pin < 0 {
                continue;
            }
            let pin = v3(pos[tether.pin as usize]);
            let d = z - pin;
            let len = d.dot(d).sqrt();
            let max = stretch * tether.rest;
            if len > max {
                on[t] = true;
                z = pin + d * (max / len);
            }
        }
        let mut shares = [none; TETHER_SLOTS];
        let mut g_tau = 0.0;
        for t in (0..TETHER_SLOTS).rev() {
            if !on[t] {
                continue;
            }
            let tether = &tethers[i][t];
            let d = before[t] - v3(pos[tether.pin as usize]);
            let len = d.dot(d).sqrt();
            let n = d * (1.0 / len);
            let max = stretch * tether.rest;
            let through = (g - n * n.dot(g)) * (max / len);
            shares[t] = v4(g - through, tether.pin as f32);
            g_tau += tether.rest * n.dot(g);
            g = through;
        }
        let mut q = p4[i];
        q[3] += g_tau;
        *o = [v4(g, 0.0), shares[0], shares[1], q];
    });
    let mut planes = planes;
    for (i, o) in out.iter().enumerate() {
        for (r, plane) in [2, 8, 9, 4].into_iter().enumerate() {
            planes[plane][i] = o[r];
        }
    }
}

/// The correction's adjoint of the strain-limited spring from `a` (mobility `wa`, count
/// `ca`, its point's gradient `ga`) to `b`, `d = x_b − x_a`.
#[allow(clippy::too_many_arguments)]
fn spring_back(p: &StepParams, ga: Vec3, d: Vec3, len: f32, rest: f32, wa: f32, wb: f32, ca: f32, cb: f32) -> Vec3 {
    let aim = 1.0 + STRAIN_AIM * p.strain_limit;
    let k = wa / ((wa + wb) * ca.max(cb).max(1.0));
    let n = d * (1.0 / len);
    k * (ga - (aim * rest / len) * (ga - n * n.dot(ga)))
}

/// `adj_strain_gather`'s twin: per particle, after [`adj_strain_back`], the gradient with
/// respect to the pass's input position (plane 0): `−v̄′/dt` plus its point's gradient
/// taken through its own over-stretched springs' corrections and its neighbours' onto it,
/// and on a pinned particle every tether's share of it; the strain limit's partial of its
/// own springs added to plane 4's w.
pub fn adj_strain_gather(
    exec: Exec,
    p: &StepParams,
    slots: &Rows<SpringSlot>,
    pos: &[V4],
    counts: &[V4],
    adjoint: &mut [V4],
) {
    let np = pos.len();
    let mut out = vec![[[0.0f32; 4]; 2]; np];
    let planes = planes(adjoint, np);
    let (vb, gp, p4, t8, t9) = (&*planes[1], &*planes[2], &*planes[4], &*planes[8], &*planes[9]);
    let stretch = 1.0 + p.strain_limit;
    for_each(exec, &mut out, |i, o| {
        let (xi, wi, ci, gi) = (v3(pos[i]), pos[i][3], counts[i][0], v3(gp[i]));
        let mut gx = gi;
        let mut g_tau = 0.0f32;
        for slot in slots.head(i) {
            if slot.neighbor < 0 {
                continue;
            }
            let b = slot.neighbor as usize;
            let d = v3(pos[b]) - xi;
            let len = d.dot(d).sqrt();
            // Over its limit as the pass decides it (a NaN length is not).
            let live = len > stretch * slot.rest;
            if !live {
                continue;
            }
            let (wb, cb) = (pos[b][3], counts[b][0]);
            if wi != 0.0 {
                gx -= spring_back(p, gi, d, len, slot.rest, wi, wb, ci, cb);
                let k = wi / ((wi + wb) * ci.max(cb).max(1.0));
                g_tau -= k * (d * (1.0 / len)).dot(gi) * slot.rest * STRAIN_AIM;
            }
            if wb != 0.0 {
                gx += spring_back(p, v3(gp[b]), -d, len, slot.rest, wb, wi, cb, ci);
            }
        }
        if wi == 0.0 {
            let me = i as f32;
            for k in 0..np {
                for share in [t8[k], t9[k]] {
                    if share[3] == me {
                        gx += v3(share);
                    }
                }
            }
        }
        let mut q = p4[i];
        q[3] += g_tau;
        *o = [v4(gx - v3(vb[i]) * (1.0 / p.dt), 0.0), q];
    });
    let mut planes = planes;
    for (i, o) in out.iter().enumerate() {
        planes[0][i] = o[0];
        planes[4][i] = o[1];
    }
}
