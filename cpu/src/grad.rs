//! Gradients through the cloth (docs/gradients.md): the CPU reference of reverse mode
//! over a recorded run. A recording keeps each frame's starting state (a checkpoint);
//! [`Recording::backward`] walks the frames backwards, recomputes each frame's substeps
//! from its checkpoint in f64 ([`Model::substep`]) and runs each substep's adjoint
//! ([`Model::adjoint`]) on the way back: memory O(frames × particles) for the
//! checkpoints plus one frame's substeps, not O(substeps).
//!
//! What it differentiates: Verlet and symplectic Euler (in the (x, v) state both are
//! `v' = (1 − damping) v + a dt`, `x' = x + v' dt`), implicit Euler (its Newton step's
//! linear solve taken exactly: the adjoint is one more solve with the same matrix), the springs (stiffness, damping and
//! their parameters in either unit), gravity, air drag, the velocity damping, the
//! cloth's mass, the floor and still spheres with the share friction, the strain limit's
//! passes and tethers (as the functions they compute: where a contact or a limit
//! switches on or off, the derivative of the side the run took), and the pinned
//! particles' positions frame by frame. What it does not yet (refused by [`Model::new`]
//! in one line): the other integrators (XPBD, RK, VBD, explicit Euler), wind, boxes, rods and bodies, moving colliders, Coulomb friction, self-contact, a
//! grabbed particle and pins moved within a frame.

use glam::DVec3;
use rayon::prelude::*;

use clothlab_core::grid::{ClothTopology, SpringKind, V4};
use clothlab_core::layout::STRAIN_AIM;
use clothlab_core::params::{Integrator, SimParams, StiffnessUnits};
use clothlab_core::scene::Scene;

/// The parameters [`Model`] differentiates, by their `set` names (`SimParams`' fields;
/// a vector's components as `gravity[0]` …).
pub const PARAMS: [&str; 17] = [
    "structural_stiffness",
    "shear_stiffness",
    "bend_stiffness",
    "structural_damping",
    "shear_damping",
    "bend_damping",
    "stretch_modulus",
    "shear_modulus",
    "bend_modulus",
    "damping",
    "air_drag",
    "cloth_mass",
    "friction",
    "gravity[0]",
    "gravity[1]",
    "gravity[2]",
    "strain_limit",
];

/// Indices into [`PARAMS`].
mod at {
    pub const KAPPA: usize = 0;
    pub const ZETA: usize = 3;
    pub const MODULUS: usize = 6;
    pub const DAMPING: usize = 9;
    pub const AIR_DRAG: usize = 10;
    pub const MASS: usize = 11;
    pub const FRICTION: usize = 12;
    pub const GRAVITY: usize = 13;
    pub const STRAIN: usize = 16;
}

/// One spring of the model: its ends, rest length, kind and mass (its lighter end's
/// for a mesh, a grid's particle mass) per kilogram of cloth.
#[derive(Debug, Clone, Copy)]
struct Spring {
    a: usize,
    b: usize,
    rest: f64,
    kind: usize,
    mass_unit: f64,
}

/// A spring's constants at the model's parameters and their derivatives by the
/// parameters of its kind (`ks` by κ or the modulus; `kd` by ζ and, in physical units,
/// the modulus) and by the cloth's mass.
#[derive(Debug, Clone, Copy, Default)]
struct Constants {
    ks: f64,
    kd: f64,
    dks: f64,
    dkd_zeta: f64,
    dkd_modulus: f64,
    dks_mass: f64,
    dkd_mass: f64,
}

/// A still sphere, grown by the collision margin.
#[derive(Debug, Clone, Copy)]
struct Ball {
    center: DVec3,
    r: f64,
}

/// The cloth's step in f64, and its adjoint: what a recording is differentiated with.
#[derive(Debug, Clone)]
pub struct Model {
    /// The parameters, [`PARAMS`]' order.
    p: [f64; PARAMS.len()],
    springs: Vec<Spring>,
    /// Each spring's constants at `p`.
    k: Vec<Constants>,
    /// Each particle's `w` (its position's: 0 pinned, else the reference mass over its own).
    w: Vec<f64>,
    /// The reference mass m̄ (a grid's particle mass) per kilogram of cloth.
    mass_unit: f64,
    dt: f64,
    substeps: u32,
    /// The floor's plane plus the margin (particles below are put on it).
    floor: f64,
    balls: Vec<Ball>,
    physical: bool,
    /// The rest spacing (the bend modulus is over its square).
    spacing: f64,
    /// The strain limit's passes a substep, each particle's held springs (the other end,
    /// the rest length) and tethers (the pin, the rest distance).
    strain_passes: u32,
    held: Vec<Vec<(usize, f64)>>,
    tethers: Vec<Vec<(usize, f64)>>,
    /// A hash of every switch the steps since [`Model::take_trace`] took (a contact or a
    /// limit on or off): two runs with the same trace took the same smooth piece, so a
    /// finite difference between them is a derivative of it.
    trace: Trace,
    /// The springs' forces on rayon's threads (`cpu-par`); else on the caller's.
    parallel: bool,
    /// Implicit Euler (else Verlet's recurrence).
    implicit: bool,
}

/// [`Model`]'s trace of switches: an atomic (the model is shared with rayon's threads),
/// copied with the model.
#[derive(Debug, Default)]
struct Trace(std::sync::atomic::AtomicU64);

impl Clone for Trace {
    fn clone(&self) -> Self {
        Self(std::sync::atomic::AtomicU64::new(self.0.load(std::sync::atomic::Ordering::Relaxed)))
    }
}

impl std::ops::Deref for Trace {
    type Target = std::sync::atomic::AtomicU64;
    fn deref(&self) -> &Self::Target {
        &self.0
    }
}

/// The gradients of a loss with respect to what a recording started from and ran with.
#[derive(Debug, Clone, PartialEq)]
pub struct Gradients {
    /// With respect to each particle's initial position (a pinned particle's: its
    /// position held from the start, the sum over the frames of [`Gradients::pins`]).
    pub positions: Vec<[f64; 3]>,
    /// With respect to each particle's initial velocity (0 for a pinned one).
    pub velocities: Vec<[f64; 3]>,
    /// With respect to each parameter of [`PARAMS`], in its order.
    pub params: Vec<(&'static str, f64)>,
    /// The pinned particles, in index order.
    pub pinned: Vec<u32>,
    /// With respect to each pinned particle's position during each frame: `pins[f][k]`
    /// for frame `f` and pinned particle `pinned[k]` (what a controller that sets the
    /// pins once a frame moves).
    pub pins: Vec<Vec<[f64; 3]>>,
}

fn d3(x: &V4) -> DVec3 {
    DVec3::new(x[0] as f64, x[1] as f64, x[2] as f64)
}

impl Model {
    /// The model of a run of `scene` (built into `topo`) with `params` from a state
    /// whose positions' w are `w`; refused in one line where the run uses what has no
    /// adjoint yet.
    pub fn new(scene: &Scene, topo: &ClothTopology, params: &SimParams, w: &[f32]) -> Result<Self, String> {
        let no = |what: &str| Err(format!("grad=True: {what} has no adjoint yet"));
        if !matches!(params.integrator, Integrator::Verlet | Integrator::SymplecticEuler | Integrator::Implicit) {
            return no(&format!("integrator {}", params.integrator.name()))
                .map_err(|e: String| e + " (verlet, symplectic-euler and implicit have)");
        }
        if params.wind != [0.0; 3] {
            return no("wind");
        }
        if params.self_collision != clothlab_core::params::SelfCollision::Off {
            return no("self-contact");
        }
        if params.static_friction > 0.0 || params.kinetic_friction > 0.0 {
            return no("Coulomb friction").map_err(|e: String| e + " (static_friction, kinetic_friction)");
        }
        if !scene.boxes.is_empty() || !scene.rods.is_empty() || !scene.bodies.is_empty() {
            return no("a box, rod or body collider");
        }
        if !scene.motions.is_empty() {
            return no("a moving collider");
        }
        if scene.pins.iter().any(|g| g.scripted || !g.motion.is_still()) {
            return no("a pin group that moves within a frame (set the pinned particles' positions between frames)");
        }
        let cloth_mass = params.cloth_mass as f64;
        let mass_unit = params.particle_mass(scene.cloth.n) as f64 / cloth_mass;
        let springs = topo
            .springs
            .iter()
            .map(|s| {
                let kind = if s.kind == SpringKind::Bend as u32 {
                    2
                } else if s.kind == SpringKind::Shear as u32 && topo.mesh.is_none() {
                    1
                } else {
                    0
                };
                let mass_unit = match &topo.mesh {
                    Some(mesh) => mesh.mass[s.a as usize].min(mesh.mass[s.b as usize]) as f64 / cloth_mass,
                    None => mass_unit,
                };
                Spring { a: s.a as usize, b: s.b as usize, rest: s.rest as f64, kind, mass_unit }
            })
            .collect();
        let p = [
            params.structural_stiffness,
            params.shear_stiffness,
            params.bend_stiffness,
            params.structural_damping,
            params.shear_damping,
            params.bend_damping,
            params.stretch_modulus,
            params.shear_modulus,
            params.bend_modulus,
            params.damping,
            params.air_drag,
            params.cloth_mass,
            params.friction,
            params.gravity[0],
            params.gravity[1],
            params.gravity[2],
            params.strain_limit,
        ]
        .map(f64::from);
        let held = (0..topo.num_particles())
            .map(|i| {
                topo.slots
                    .head(i)
                    .iter()
                    .filter(|s| s.neighbor >= 0)
                    .map(|s| (s.neighbor as usize, s.rest as f64))
                    .collect()
            })
            .collect();
        let tethers = topo
            .tethers
            .iter()
            .map(|ts| ts.iter().filter(|t| t.pin >= 0).map(|t| (t.pin as usize, t.rest as f64)).collect())
            .collect();
        let balls = scene
            .spheres
            .iter()
            .map(|s| Ball {
                center: DVec3::from(s.center.map(f64::from)),
                r: (s.radius + params.collision_margin) as f64,
            })
            .collect();
        let mut m = Self {
            p,
            springs,
            k: Vec::new(),
            w: w.iter().map(|&w| w as f64).collect(),
            mass_unit,
            dt: params.dt() as f64,
            substeps: params.substeps,
            // As the step computes it: the floor's height plus the margin, in f32.
            floor: (scene.floor_height() + params.collision_margin) as f64,
            balls,
            physical: params.stiffness_units == StiffnessUnits::Physical,
            spacing: topo.spacing as f64,
            strain_passes: params.strain_iterations,
            held,
            tethers,
            trace: Trace::default(),
            parallel: false,
            implicit: params.integrator == Integrator::Implicit,
        };
        m.derive();
        Ok(m)
    }

    /// This model with its springs' forces on rayon's threads (`cpu-par`) or not.
    pub fn parallel(mut self, on: bool) -> Self {
        self.parallel = on;
        self
    }

    /// The parameters, [`PARAMS`]' order.
    pub fn params(&self) -> [f64; PARAMS.len()] {
        self.p
    }

    /// Parameter `k` of [`PARAMS`] set to `value` (the springs' constants follow).
    pub fn set_param(&mut self, k: usize, value: f64) {
        self.p[k] = value;
        self.derive();
    }

    /// Each spring's constants from the parameters (`SimParams::spring_constants_for_mass`
    /// in f64): `κ m/dt²` and `ζ m/dt` as fractions of the stability limit, or the modulus
    /// (the bend's over the spacing²) and `ζ 2 √(k m)` in physical units.
    fn derive(&mut self) {
        let (dt, mass) = (self.dt, self.p[at::MASS]);
        let bend = 1.0 / (self.spacing * self.spacing).max(1e-12);
        self.k = self
            .springs
            .iter()
            .map(|s| {
                let m = s.mass_unit * mass;
                let (kappa, zeta) = (self.p[at::KAPPA + s.kind], self.p[at::ZETA + s.kind]);
                if self.physical {
                    let dmod = if s.kind == 2 { bend } else { 1.0 };
                    let k = self.p[at::MODULUS + s.kind] * dmod;
                    let root = (k * m).sqrt();
                    Constants {
                        ks: k,
                        kd: zeta * 2.0 * root,
                        dks: dmod,
                        dkd_zeta: 2.0 * root,
                        dkd_modulus: if k > 0.0 { zeta * (m / k).sqrt() * dmod } else { 0.0 },
                        dks_mass: 0.0,
                        dkd_mass: if m > 0.0 { zeta * (k / m).sqrt() * s.mass_unit } else { 0.0 },
                    }
                } else {
                    Constants {
                        ks: kappa * m / (dt * dt),
                        kd: zeta * m / dt,
                        dks: m / (dt * dt),
                        dkd_zeta: m / dt,
                        dkd_modulus: 0.0,
                        dks_mass: kappa * s.mass_unit / (dt * dt),
                        dkd_mass: zeta * s.mass_unit / dt,
                    }
                }
            })
            .collect();
    }

    /// The reference mass m̄.
    fn mass(&self) -> f64 {
        self.mass_unit * self.p[at::MASS]
    }

    fn gravity(&self) -> DVec3 {
        DVec3::new(self.p[at::GRAVITY], self.p[at::GRAVITY + 1], self.p[at::GRAVITY + 2])
    }

    /// The trace of the switches the steps took since the last call, cleared: a hash of
    /// every contact or limit switched on or off (two runs with the same trace took the
    /// same smooth piece).
    pub fn take_trace(&self) -> u64 {
        self.trace.swap(0, std::sync::atomic::Ordering::Relaxed)
    }

    /// Notes a switch (on or off) in the trace.
    fn note(&self, on: bool) {
        use std::sync::atomic::Ordering::Relaxed;
        let t = self.trace.load(Relaxed);
        self.trace.store(t.rotate_left(7).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ u64::from(on), Relaxed);
    }

    /// The parameters' gradients from the adjoint kernels' partials summed over the
    /// particles ([`crate::adjoint::partial_sums`]): gravity, air drag, damping and
    /// friction as they are; the particle mass's onto the cloth's; each spring family's
    /// `Σ ∂/∂ks`, `Σ ∂/∂kd` times its constants' derivatives where the family's springs
    /// share them (a grid's), else `Σ ks ∂/∂ks` and `Σ kd ∂/∂kd` over the parameter (a
    /// mesh's springs, whose constants follow their masses: refused where that parameter
    /// is 0).
    pub fn params_from_partials(&self, s: &[f64; crate::adjoint::PARTIALS]) -> Result<[f64; PARAMS.len()], String> {
        let mut g = [0.0; PARAMS.len()];
        use crate::adjoint::Partial as P;
        let sum = |q: P| {
            let (plane, c) = q.at();
            s[4 * (plane - 3) + c]
        };
        for c in 0..3 {
            g[at::GRAVITY + c] = sum(P::Gravity(c));
        }
        g[at::AIR_DRAG] = sum(P::AirDrag);
        g[at::DAMPING] = sum(P::Damping);
        g[at::FRICTION] = sum(P::Friction);
        g[at::STRAIN] = sum(P::StrainLimit);
        let mass = self.p[at::MASS];
        g[at::MASS] = sum(P::ParticleMass) * self.mass_unit;
        for kind in 0..3 {
            let [sks, skd, lks, lkd] = [0, 1, 2, 3].map(|c| sum(P::Spring(kind, c)));
            let of_kind: Vec<&Constants> =
                self.springs.iter().zip(&self.k).filter(|(sp, _)| sp.kind == kind).map(|(_, k)| k).collect();
            let Some(k0) = of_kind.first() else { continue };
            let shared = of_kind.iter().all(|k| k.ks == k0.ks && k.kd == k0.kd);
            let over = |l: f64, at: usize| -> Result<f64, String> {
                match (shared, self.p[at]) {
                    (true, _) => unreachable!("shared constants take the sums"),
                    (false, v) if v != 0.0 => Ok(l / v),
                    _ => Err(format!(
                        "grad=True: {} = 0 on a mesh: its gradient from the adjoint kernels needs it non-zero",
                        PARAMS[at]
                    )),
                }
            };
            if self.physical {
                // ks = the modulus (over the spacing², bend), shared; kd = ζ 2 √(ks m).
                g[at::MODULUS + kind] += sks * k0.dks;
                g[at::MODULUS + kind] += if shared {
                    skd * k0.dkd_modulus
                } else if k0.ks > 0.0 {
                    lkd / (2.0 * k0.ks) * k0.dks
                } else {
                    0.0
                };
                g[at::ZETA + kind] += if shared { skd * k0.dkd_zeta } else { over(lkd, at::ZETA + kind)? };
                g[at::MASS] += lkd / (2.0 * mass);
            } else {
                // ks = κ m/dt², kd = ζ m/dt: both in proportion to the mass.
                g[at::KAPPA + kind] += if shared { sks * k0.dks } else { over(lks, at::KAPPA + kind)? };
                g[at::ZETA + kind] += if shared { skd * k0.dkd_zeta } else { over(lkd, at::ZETA + kind)? };
                g[at::MASS] += (lks + lkd) / mass;
            }
        }
        Ok(g)
    }

    /// Substeps a frame.
    pub fn substeps(&self) -> u32 {
        self.substeps
    }

    /// The pinned particles (w = 0), in index order.
    pub fn pinned(&self) -> Vec<u32> {
        (0..self.w.len() as u32).filter(|&i| self.w[i as usize] == 0.0).collect()
    }

    /// Each particle's spring force at `(x, v)`: `−(ks (|l| − r) + kd (l̇·l̂)) l̂` on end a,
    /// its opposite on end b (`cpu::springs`).
    fn forces(&self, x: &[DVec3], v: &[DVec3]) -> Vec<DVec3> {
        let each: Vec<DVec3> = self
            .springs
            .par_iter()
            .zip(&self.k)
            .with_min_len(if self.parallel { 4096 } else { usize::MAX })
            .map(|(s, k)| {
                let l = x[s.a] - x[s.b];
                let len = l.length();
                if len <= f64::MIN_POSITIVE {
                    return DVec3::ZERO;
                }
                let dir = l / len;
                -(k.ks * (len - s.rest) + k.kd * (v[s.a] - v[s.b]).dot(dir)) * dir
            })
            .collect();
        let mut f = vec![DVec3::ZERO; x.len()];
        for (s, fs) in self.springs.iter().zip(each) {
            f[s.a] += fs;
            f[s.b] -= fs;
        }
        f
    }

    /// One substep from `(x, v)` in place (`cpu::integrate`, `cpu::collide`, then the
    /// strain limit's passes): every free particle's `v ← (1 − damping) v + (w/m̄ f + g −
    /// air_drag v) dt`, `x ← x + v dt`, the floor, then the spheres in scene order; a
    /// pinned one still.
    pub fn substep(&self, x: &mut [DVec3], v: &mut [DVec3]) {
        self.integrate(x, v);
        for _ in 0..self.strain_passes {
            self.strain_pass(x, v);
        }
    }

    /// The substep's integration and contacts (before the strain limit).
    fn integrate(&self, x: &mut [DVec3], v: &mut [DVec3]) {
        let f = self.forces(x, v);
        self.integrate_with(&f, x, v);
    }

    /// [`Model::integrate`] with the springs' forces at `(x, v)` given.
    fn integrate_with(&self, f: &[DVec3], x: &mut [DVec3], v: &mut [DVec3]) {
        let vt = self.velocities(f, x, v);
        for i in 0..x.len() {
            if self.w[i] == 0.0 {
                v[i] = DVec3::ZERO;
                continue;
            }
            let (xn, vn) = self.floor(x[i] + vt[i] * self.dt, vt[i]);
            let (xn, vn) = self.balls.iter().fold((xn, vn), |(x, v), b| self.ball(b, x, v).unwrap_or((x, v)));
            (x[i], v[i]) = (xn, vn);
        }
    }

    /// Each free particle's velocity at the substep's end before the contacts: Verlet's
    /// `(1 − damping) v + (w/m̄ f + g − air_drag v) dt`, or implicit Euler's `(1 −
    /// damping) v + Δv` (a held particle's: unused).
    fn velocities(&self, f: &[DVec3], x: &[DVec3], v: &[DVec3]) -> Vec<DVec3> {
        let (mass, g, drag, damping) = (self.mass(), self.gravity(), self.p[at::AIR_DRAG], self.p[at::DAMPING]);
        if self.implicit {
            let dv = self.newton_step(f, x, v);
            return v.iter().zip(dv).map(|(v, dv)| *v * (1.0 - damping) + dv).collect();
        }
        (0..x.len())
            .map(|i| {
                let a = f[i] * (self.w[i] / mass) + g - v[i] * drag;
                v[i] * (1.0 - damping) + a * self.dt
            })
            .collect()
    }

    /// Particle `i`'s mass (a free one's: m̄/w).
    fn mass_of(&self, i: usize) -> f64 {
        self.mass() / self.w[i]
    }

    /// Implicit Euler's Newton step in velocities (`cpu::integrators`' `cg_begin` …
    /// `implicit_finish`): `A Δv = dt (f + m g − air_drag m v) − dt² K v` over the free
    /// particles, `A = m (1 + dt air_drag) I + Σₛ (dt² Kₛ + dt Dₛ)`, `Kₛ = ks [n nᵀ +
    /// max(0, 1 − rest/len) (I − n nᵀ)]`, `Dₛ = kd n nᵀ`; solved to f64's rounding (the
    /// solver's `cg_iterations` truncate it: measured 1e-6 m apart after 30 frames at 64).
    fn newton_step(&self, f: &[DVec3], x: &[DVec3], v: &[DVec3]) -> Vec<DVec3> {
        let (g, drag, dt) = (self.gravity(), self.p[at::AIR_DRAG], self.dt);
        // Kₛ's part across the spring switches on as it stretches past its rest length.
        for s in &self.springs {
            self.note((x[s.a] - x[s.b]).length() > s.rest);
        }
        let kv = self.implicit_apply(x, v, false);
        let b: Vec<DVec3> = (0..x.len())
            .map(|i| {
                if self.w[i] == 0.0 {
                    return DVec3::ZERO;
                }
                let m = self.mass_of(i);
                (f[i] + m * g - drag * m * v[i]) * dt - kv[i]
            })
            .collect();
        self.solve(x, &b)
    }

    /// `(A y)ᵢ` for every free particle (0 for a held one), or without the mass and the
    /// springs' damping (`full` false): `dt² (K y)ᵢ`.
    fn implicit_apply(&self, x: &[DVec3], y: &[DVec3], full: bool) -> Vec<DVec3> {
        let (drag, dt) = (self.p[at::AIR_DRAG], self.dt);
        let mut out: Vec<DVec3> = (0..x.len())
            .map(|i| if full && self.w[i] != 0.0 { y[i] * self.mass_of(i) * (1.0 + dt * drag) } else { DVec3::ZERO })
            .collect();
        for (s, k) in self.springs.iter().zip(&self.k) {
            let d = x[s.a] - x[s.b];
            let len = d.length();
            if len <= f64::MIN_POSITIVE {
                continue;
            }
            let n = d / len;
            let soft = (1.0 - s.rest / len).max(0.0);
            let yd = y[s.a] - y[s.b];
            let ny = n.dot(yd);
            let (k2, c) = (k.ks * dt * dt, if full { k.kd * dt } else { 0.0 });
            let t = n * ((k2 + c) * ny) + (yd - n * ny) * (k2 * soft);
            out[s.a] += t;
            out[s.b] -= t;
        }
        for (i, o) in out.iter_mut().enumerate() {
            if self.w[i] == 0.0 {
                *o = DVec3::ZERO;
            }
        }
        out
    }

    /// `A⁻¹ b` over the free particles (a held one's row 0), by conjugate gradients
    /// preconditioned with A's diagonal, to a residual of 1e-13 of `b`'s.
    fn solve(&self, x: &[DVec3], b: &[DVec3]) -> Vec<DVec3> {
        let (drag, dt) = (self.p[at::AIR_DRAG], self.dt);
        let mut diag: Vec<f64> =
            (0..x.len()).map(|i| if self.w[i] == 0.0 { 0.0 } else { self.mass_of(i) * (1.0 + dt * drag) }).collect();
        for (s, k) in self.springs.iter().zip(&self.k) {
            let len = (x[s.a] - x[s.b]).length();
            if len <= f64::MIN_POSITIVE {
                continue;
            }
            let soft = (1.0 - s.rest / len).max(0.0);
            let t = (k.ks * dt * dt * (1.0 + 2.0 * soft) + k.kd * dt) / 3.0;
            for e in [s.a, s.b] {
                if self.w[e] != 0.0 {
                    diag[e] += t;
                }
            }
        }
        let dot = |a: &[DVec3], b: &[DVec3]| a.iter().zip(b).map(|(a, b)| a.dot(*b)).sum::<f64>();
        let pre = |r: &[DVec3]| -> Vec<DVec3> {
            r.iter().zip(&diag).map(|(r, d)| if *d > 0.0 { *r / *d } else { DVec3::ZERO }).collect()
        };
        let mut r: Vec<DVec3> =
            b.iter().enumerate().map(|(i, b)| if self.w[i] == 0.0 { DVec3::ZERO } else { *b }).collect();
        let mut sol = vec![DVec3::ZERO; x.len()];
        let stop = 1e-26 * dot(&r, &r);
        let mut z = pre(&r);
        let mut p = z.clone();
        let mut rz = dot(&r, &z);
        for _ in 0..4 * x.len() + 64 {
            if dot(&r, &r) <= stop || rz <= 0.0 {
                break;
            }
            let q = self.implicit_apply(x, &p, true);
            let alpha = rz / dot(&p, &q);
            for i in 0..x.len() {
                sol[i] += alpha * p[i];
                r[i] -= alpha * q[i];
            }
            z = pre(&r);
            let next = dot(&r, &z);
            let beta = next / rz;
            rz = next;
            for (p, z) in p.iter_mut().zip(&z) {
                *p = *z + beta * *p;
            }
        }
        sol
    }

    /// The adjoint of [`Model::newton_step`] onto `dvb` (the gradient with respect to
    /// `Δv`): `λ = A⁻¹ dvb` (A is symmetric), then `λᵀ ∂(b − A Δv)/∂·` onto the
    /// positions, velocities and parameters (the residual's, as `Δv` solves it: the
    /// implicit function's derivative).
    #[allow(clippy::too_many_arguments)]
    fn newton_adjoint(
        &self,
        x: &[DVec3],
        v: &[DVec3],
        dv: &[DVec3],
        dvb: &[DVec3],
        xin: &mut [DVec3],
        vin: &mut [DVec3],
        params: &mut [f64],
    ) {
        let lam = self.solve(x, dvb);
        let (g, drag, dt, big_m) = (self.gravity(), self.p[at::AIR_DRAG], self.dt, self.p[at::MASS]);
        for i in 0..x.len() {
            if self.w[i] == 0.0 {
                continue;
            }
            // Rᵢ ∋ dt m (g − air_drag v) − m (1 + dt air_drag) Δv.
            let (m, l) = (self.mass_of(i), lam[i]);
            for c in 0..3 {
                params[at::GRAVITY + c] += dt * m * l[c];
            }
            params[at::AIR_DRAG] -= dt * m * l.dot(v[i] + dv[i]);
            vin[i] -= l * (dt * drag * m);
            params[at::MASS] += l.dot((g - drag * v[i]) * (dt * m) - dv[i] * (m * (1.0 + dt * drag))) / big_m;
        }
        // A spring's part of R at its end a (its opposite at b):
        // dt fₛ − dt² Kₛ (u + δ) − dt Dₛ δ, u = v_a − v_b, δ = Δv_a − Δv_b;
        // φ = (λ_a − λ_b)·that, differentiated by d = x_a − x_b, u, ks and kd.
        for (s, k) in self.springs.iter().zip(&self.k) {
            let e = lam[s.a] - lam[s.b];
            let d = x[s.a] - x[s.b];
            let len = d.length();
            if e == DVec3::ZERO || len <= f64::MIN_POSITIVE {
                continue;
            }
            let n = d / len;
            let (u, delta) = (v[s.a] - v[s.b], dv[s.a] - dv[s.b]);
            let z = u + delta;
            let open = 1.0 - s.rest / len;
            let (soft, dsoft) = if open > 0.0 { (open, s.rest / (len * len)) } else { (0.0, 0.0) };
            let (ne, nz, nu, nd) = (n.dot(e), n.dot(z), n.dot(u), n.dot(delta));
            let stretch = len - s.rest;
            let (dt2, ks, kd) = (dt * dt, k.ks, k.kd);
            let gn = -dt * kd * ne * u
                - dt * (ks * stretch + kd * nu) * e
                - dt2 * ks * (1.0 - soft) * (nz * e + ne * z)
                - dt * kd * (nd * e + ne * delta);
            let glen = -dt * ks * ne - dt2 * ks * (e.dot(z) - ne * nz) * dsoft;
            let gd = (gn - n * n.dot(gn)) / len + n * glen;
            let gu = -dt * kd * ne * n - dt2 * ks * ((1.0 - soft) * ne * n + soft * e);
            xin[s.a] += gd;
            xin[s.b] -= gd;
            vin[s.a] += gu;
            vin[s.b] -= gu;
            let gks = -dt * stretch * ne - dt2 * ((1.0 - soft) * ne * nz + soft * e.dot(z));
            let gkd = -dt * nu * ne - dt * ne * nd;
            self.spring_partials(s, k, gks, gkd, params);
        }
    }

    /// A spring's `∂/∂ks`, `∂/∂kd` onto the parameters its constants follow.
    fn spring_partials(&self, s: &Spring, k: &Constants, gks: f64, gkd: f64, params: &mut [f64]) {
        if self.physical {
            params[at::MODULUS + s.kind] += gks * k.dks + gkd * k.dkd_modulus;
        } else {
            params[at::KAPPA + s.kind] += gks * k.dks;
        }
        params[at::ZETA + s.kind] += gkd * k.dkd_zeta;
        params[at::MASS] += gks * k.dks_mass + gkd * k.dkd_mass;
    }

    /// Particle `i`'s position after one strain pass over `x` (`cpu::strain_limit`'s
    /// `limit_at` in f64): its over-stretched held springs' corrections (each shared by
    /// mobility and divided by the larger of its ends' counts), then its tethers. With
    /// `back`, the adjoint: `g` (the gradient with respect to the result) taken back onto
    /// `xb` (of every position it read) and the strain limit's parameter.
    fn strain_at(
        &self,
        i: usize,
        x: &[DVec3],
        counts: &[f64],
        back: Option<(DVec3, &mut [DVec3], &mut [f64])>,
    ) -> DVec3 {
        let tau = self.p[at::STRAIN];
        let (stretch, aim) = (1.0 + tau, 1.0 + STRAIN_AIM as f64 * tau);
        let wi = self.w[i];
        if wi == 0.0 {
            if let Some((g, xb, _)) = back {
                xb[i] += g;
            }
            return x[i];
        }
        // The springs: c = k (d − A n), k = wᵢ/((wᵢ + w_b) m), A = aim·rest.
        let live = |&(b, rest): &(usize, f64)| {
            let d = x[b] - x[i];
            let len = d.length();
            (len > stretch * rest).then(|| {
                let k = wi / ((wi + self.w[b]) * counts[i].max(counts[b]).max(1.0));
                (b, rest, d, len, k)
            })
        };
        let mut z = x[i];
        for (_, rest, d, len, k) in self.held[i].iter().filter_map(live) {
            z += k * (d - aim * rest * d / len);
        }
        // The tethers, in order: each a projection onto the sphere about its pin.
        let mut chain = Vec::new();
        for &(pin, rest) in &self.tethers[i] {
            let d = z - x[pin];
            let len = d.length();
            let max = stretch * rest;
            // A point a pass before put on the sphere sits on it to rounding: on either
            // side of it the derivative is the projection's (P·P = P), no switch.
            if (len - max).abs() > 1e-12 * max {
                self.note(len > max);
            }
            if len > max {
                chain.push((pin, rest, z));
                z = x[pin] + d * (max / len);
            }
        }
        if let Some((mut g, xb, params)) = back {
            for &(pin, rest, before) in chain.iter().rev() {
                let d = before - x[pin];
                let len = d.length();
                let n = d / len;
                let max = stretch * rest;
                let through = (g - n * n.dot(g)) * (max / len);
                xb[pin] += g - through;
                params[at::STRAIN] += rest * n.dot(g);
                g = through;
            }
            xb[i] += g;
            for (b, rest, d, len, k) in self.held[i].iter().filter_map(live) {
                let n = d / len;
                // ∂c/∂d = k (I − (A/len)(I − n nᵀ)), symmetric.
                let a = aim * rest;
                let md = k * (g - (a / len) * (g - n * n.dot(g)));
                xb[b] += md;
                xb[i] -= md;
                params[at::STRAIN] -= k * n.dot(g) * rest * STRAIN_AIM as f64;
            }
        }
        z
    }

    /// Each particle's count of over-stretched held springs at `x` (`cpu::strain_count`).
    fn strain_counts(&self, x: &[DVec3]) -> Vec<f64> {
        let stretch = 1.0 + self.p[at::STRAIN];
        (0..x.len())
            .map(|i| {
                let over = |&&(b, rest): &&(usize, f64)| (x[b] - x[i]).length() > stretch * rest;
                let c = self.held[i].iter().filter(over).count();
                self.note(c > 0);
                self.trace.fetch_xor(c as u64, std::sync::atomic::Ordering::Relaxed);
                c as f64
            })
            .collect()
    }

    /// One strain pass in place: the positions corrected, the velocities by the move over
    /// the substep (`cpu::strain_vel`).
    fn strain_pass(&self, x: &mut [DVec3], v: &mut [DVec3]) {
        let counts = self.strain_counts(x);
        let y: Vec<DVec3> = (0..x.len()).map(|i| self.strain_at(i, x, &counts, None)).collect();
        for ((xi, vi), yi) in x.iter_mut().zip(v.iter_mut()).zip(&y) {
            *vi += (*yi - *xi) / self.dt;
            *xi = *yi;
        }
    }

    /// The adjoint of [`Model::strain_pass`] at its input `x`: `xb`, `vb` from the
    /// gradient with respect to its output to the one with respect to its input.
    fn strain_adjoint(&self, x: &[DVec3], xb: &mut [DVec3], vb: &[DVec3], params: &mut [f64]) {
        let counts = self.strain_counts(x);
        // v' = v + (y − x)/dt: ȳ = x̄' + v̄'/dt, x̄ = J_yᵀ ȳ − v̄'/dt, v̄ = v̄'.
        let gy: Vec<DVec3> = xb.iter().zip(vb).map(|(gx, gv)| *gx + *gv / self.dt).collect();
        for (g, gv) in xb.iter_mut().zip(vb) {
            *g = -*gv / self.dt;
        }
        for (i, &g) in gy.iter().enumerate() {
            self.strain_at(i, x, &counts, Some((g, &mut *xb, &mut *params)));
        }
    }

    /// The share friction's velocity at a contact of normal `n` (`contact_vel`).
    fn slide(&self, v: DVec3, n: DVec3) -> DVec3 {
        let vn = v.dot(n);
        self.note(vn > 0.0);
        (v - vn * n) * (1.0 - self.p[at::FRICTION]) + vn.max(0.0) * n
    }

    fn floor(&self, mut x: DVec3, v: DVec3) -> (DVec3, DVec3) {
        self.note(x.y < self.floor);
        if x.y < self.floor {
            x.y = self.floor;
            return (x, self.slide(v, DVec3::Y));
        }
        (x, v)
    }

    /// A sphere's contact: the point put on the grown surface, the velocity slid.
    fn ball(&self, b: &Ball, x: DVec3, v: DVec3) -> Option<(DVec3, DVec3)> {
        let d = x - b.center;
        let dist = d.length();
        self.note(dist < b.r);
        if dist >= b.r || dist <= 0.0 {
            return None;
        }
        let n = d / dist;
        Some((b.center + n * b.r, self.slide(v, n)))
    }

    /// The adjoint of [`Model::substep`] at its input `(x, v)`: `xb`, `vb` hold the
    /// loss's gradient with respect to the substep's output and become its gradient with
    /// respect to the input; the parameters' gradients are added to `params`
    /// ([`PARAMS`]' order). A pinned particle's `xb` gathers what its position is worth
    /// (the caller takes it to the frame's pins).
    pub fn adjoint(&self, x: &[DVec3], v: &[DVec3], xb: &mut [DVec3], vb: &mut [DVec3], params: &mut [f64]) {
        let f = self.forces(x, v);
        if self.strain_passes > 0 {
            // Back through the strain passes, last first: each one's input again.
            let (mut xs, mut vs) = (x.to_vec(), v.to_vec());
            self.integrate_with(&f, &mut xs, &mut vs);
            let mut inputs = Vec::with_capacity(self.strain_passes as usize);
            for _ in 0..self.strain_passes {
                inputs.push(xs.clone());
                self.strain_pass(&mut xs, &mut vs);
            }
            for input in inputs.iter().rev() {
                self.strain_adjoint(input, xb, vb, params);
            }
        }
        let np = x.len();
        let (mass, drag, damping) = (self.mass(), self.p[at::AIR_DRAG], self.p[at::DAMPING]);
        let vts = self.velocities(&f, x, v);
        // The gradient with respect to each free particle's acceleration (Verlet) or
        // Newton step (implicit).
        let mut ab = vec![DVec3::ZERO; np];
        let mut xin = vec![DVec3::ZERO; np];
        let mut vin = vec![DVec3::ZERO; np];
        for i in 0..np {
            if self.w[i] == 0.0 {
                // x' = x, v' = 0.
                xin[i] = xb[i];
                continue;
            }
            // Forward again, keeping what the adjoint needs.
            let vt = vts[i];
            let xt = x[i] + vt * self.dt;
            let floored = xt.y < self.floor;
            let (mut xc, mut vc) = self.floor(xt, vt);
            let mut hits = Vec::new();
            for b in &self.balls {
                if let Some(next) = self.ball(b, xc, vc) {
                    hits.push((*b, xc, vc));
                    (xc, vc) = next;
                }
            }
            // Back through the spheres, last first.
            let (mut gx, mut gv) = (xb[i], vb[i]);
            for (b, xh, vh) in hits.into_iter().rev() {
                (gx, gv) = self.ball_adjoint(&b, xh, vh, gx, gv, params);
            }
            // The floor.
            if floored {
                gx.y = 0.0;
                gv = self.slide_adjoint(vt, DVec3::Y, gv, params).0;
            }
            // x' = x + v' dt.
            let gvt = gv + gx * self.dt;
            xin[i] += gx;
            // v' = (1 − damping) v + a dt (Verlet), or + Δv (implicit).
            vin[i] += gvt * (1.0 - damping);
            params[at::DAMPING] -= v[i].dot(gvt);
            if self.implicit {
                ab[i] = gvt;
                continue;
            }
            let g = gvt * self.dt;
            ab[i] = g;
            // a = w/m̄ f + g − air_drag v.
            for c in 0..3 {
                params[at::GRAVITY + c] += g[c];
            }
            params[at::AIR_DRAG] -= v[i].dot(g);
            vin[i] -= g * drag;
            // ∂(w/m̄)/∂M = −(w/m̄)/M.
            params[at::MASS] -= f[i].dot(g) * (self.w[i] / mass) / self.p[at::MASS];
        }
        if self.implicit {
            let dv: Vec<DVec3> = vts.iter().zip(v).map(|(vt, v)| *vt - *v * (1.0 - damping)).collect();
            self.newton_adjoint(x, v, &dv, &ab, &mut xin, &mut vin, params);
            xb.copy_from_slice(&xin);
            vb.copy_from_slice(&vin);
            return;
        }
        // The springs: f̄ on each from its ends' accelerations.
        for (s, k) in self.springs.iter().zip(&self.k) {
            let l = x[s.a] - x[s.b];
            let len = l.length();
            if len <= f64::MIN_POSITIVE {
                continue;
            }
            let fb = ab[s.a] * (self.w[s.a] / mass) - ab[s.b] * (self.w[s.b] / mass);
            let dir = l / len;
            let dv = v[s.a] - v[s.b];
            let stretch = len - s.rest;
            let rate = dv.dot(dir);
            let sc = k.ks * stretch + k.kd * rate;
            let along = dir.dot(fb);
            // f = −sc l̂: ∂/∂l and ∂/∂l̇ transposed onto f̄.
            let gl = -along * (k.ks * dir + k.kd * (dv - rate * dir) / len) - (sc / len) * (fb - along * dir);
            let gdv = -k.kd * along * dir;
            xin[s.a] += gl;
            xin[s.b] -= gl;
            vin[s.a] += gdv;
            vin[s.b] -= gdv;
            self.spring_partials(s, k, -stretch * along, -rate * along, params);
        }
        xb.copy_from_slice(&xin);
        vb.copy_from_slice(&vin);
    }

    /// The adjoint of [`Model::slide`] at `(v, n)` onto `gv`: the gradients with respect to
    /// `v` and `n`; friction's added to `params`.
    fn slide_adjoint(&self, v: DVec3, n: DVec3, gv: DVec3, params: &mut [f64]) -> (DVec3, DVec3) {
        let vn = v.dot(n);
        let keep = 1.0 - self.p[at::FRICTION];
        let on = if vn > 0.0 { 1.0 } else { 0.0 };
        // v' = (v − vn n) keep + on vn n.
        let gvn = n.dot(gv);
        let g_v = (gv - gvn * n) * keep + on * gvn * n;
        // ∂v'/∂n = (on − keep)(vn I + n vᵀ), transposed: (on − keep)(vn gv + v (n·gv)).
        let g_n = (on - keep) * (vn * gv + v * gvn);
        params[at::FRICTION] -= (v - vn * n).dot(gv);
        (g_v, g_n)
    }

    /// The adjoint of a sphere's contact at `(x, v)` onto `(gx, gv)` (with respect to its
    /// output point and velocity): with respect to `x` and `v`.
    fn ball_adjoint(&self, b: &Ball, x: DVec3, v: DVec3, gx: DVec3, gv: DVec3, params: &mut [f64]) -> (DVec3, DVec3) {
        let d = x - b.center;
        let dist = d.length();
        let n = d / dist;
        let (g_v, g_n) = self.slide_adjoint(v, n, gv, params);
        // at = c + r n; n = d/|d|: ∂n/∂x = (I − n nᵀ)/|d| (symmetric).
        let gn = g_n + gx * b.r;
        ((gn - n.dot(gn) * n) / dist, g_v)
    }
}

/// A recorded run: the model and each frame's starting state.
#[derive(Debug, Clone)]
pub struct Recording {
    model: Model,
    checkpoints: Vec<(Vec<DVec3>, Vec<DVec3>)>,
}

impl Recording {
    /// An empty recording of runs with `model`.
    pub fn new(model: Model) -> Self {
        Self { model, checkpoints: Vec::new() }
    }

    /// The model.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The model, to change a parameter ([`Model::set_param`]: finite differences).
    pub fn model_mut(&mut self) -> &mut Model {
        &mut self.model
    }

    /// Frame `f`'s starting positions and velocities (finite differences move them; a
    /// replay takes the free particles from frame 0's and the pinned ones from each
    /// frame's).
    pub fn checkpoint_mut(&mut self, f: usize) -> (&mut [DVec3], &mut [DVec3]) {
        let (x, v) = &mut self.checkpoints[f];
        (x, v)
    }

    /// Frames recorded.
    pub fn frames(&self) -> usize {
        self.checkpoints.len()
    }

    /// Bytes the checkpoints hold.
    pub fn bytes(&self) -> usize {
        self.checkpoints.iter().map(|(x, v)| (x.len() + v.len()) * std::mem::size_of::<DVec3>()).sum()
    }

    /// Keeps the state a frame starts from (positions' w must be the model's).
    pub fn push(&mut self, pos: &[V4], vel: &[V4]) {
        self.checkpoints.push((pos.iter().map(d3).collect(), vel.iter().map(d3).collect()));
    }

    /// The recorded frames run again in f64 from the first checkpoint (the pinned
    /// particles set from each frame's): the final positions and velocities.
    pub fn replay(&self) -> (Vec<DVec3>, Vec<DVec3>) {
        let Some((x0, v0)) = self.checkpoints.first() else { return (Vec::new(), Vec::new()) };
        self.model.take_trace();
        let (mut x, mut v) = (x0.clone(), v0.clone());
        for (cx, _) in &self.checkpoints {
            for (i, p) in x.iter_mut().enumerate() {
                if self.model.w[i] == 0.0 {
                    *p = cx[i];
                }
            }
            for _ in 0..self.model.substeps {
                self.model.substep(&mut x, &mut v);
            }
        }
        (x, v)
    }

    /// This recording with every frame's checkpoint replaced by the f64 replay's state
    /// at that frame (the pinned particles as recorded): what a run of the model in f64
    /// from the first checkpoint would have recorded, so that [`Recording::backward`] is
    /// exactly the derivative of [`Recording::replay`] (the f32 run's checkpoints differ
    /// from it by the f32 rounding of the run, which moves the point each frame's
    /// derivative is taken at: measured 1e-4 … 2e-3 of a gradient on a drape of 12
    /// frames).
    pub fn in_f64(&self) -> Self {
        let mut out = self.clone();
        let Some((x0, v0)) = self.checkpoints.first() else { return out };
        let (mut x, mut v) = (x0.clone(), v0.clone());
        for (f, (cx, _)) in self.checkpoints.iter().enumerate() {
            for (i, p) in x.iter_mut().enumerate() {
                if self.model.w[i] == 0.0 {
                    *p = cx[i];
                }
            }
            out.checkpoints[f] = (x.clone(), v.clone());
            for _ in 0..self.model.substeps {
                self.model.substep(&mut x, &mut v);
            }
        }
        out
    }

    /// The gradients of a loss whose gradient with respect to the final positions and
    /// velocities is `xb`, `vb` (either may be all zeros), back through every recorded
    /// frame: each frame's substeps recomputed from its checkpoint, then their adjoints
    /// (the f64 model's: [`Model::substep`], [`Model::adjoint`]).
    pub fn backward(&self, xb: &[[f32; 3]], vb: &[[f32; 3]]) -> Gradients {
        self.backward_by(&mut ModelWalk, xb, vb).expect("the model's walk does not fail")
    }

    /// [`Recording::backward`] with the substeps recomputed and walked back by `walk`
    /// (the f64 model, or the adjoint kernels on a kernel runner).
    pub fn backward_by(&self, walk: &mut dyn Walk, xb: &[[f32; 3]], vb: &[[f32; 3]]) -> Result<Gradients, String> {
        let m = &self.model;
        let mut gx: Vec<DVec3> = xb.iter().map(|g| DVec3::from(g.map(f64::from))).collect();
        let mut gv: Vec<DVec3> = vb.iter().map(|g| DVec3::from(g.map(f64::from))).collect();
        let mut params = vec![0.0; PARAMS.len()];
        let pinned = m.pinned();
        let frames = self.checkpoints.len();
        let mut pins = vec![vec![[0.0; 3]; pinned.len()]; frames];
        for f in (0..frames).rev() {
            // The frame's substeps again: each one's input.
            let (x, v) = &self.checkpoints[f];
            let path = walk.inputs(m, x, v)?;
            for (x, v) in path.iter().rev() {
                walk.adjoint(m, x, v, &mut gx, &mut gv, &mut params)?;
            }
            // A pinned particle's position is the frame's pin: its gradient is the
            // frame's, not carried to the frame before (which set its own).
            for (k, &i) in pinned.iter().enumerate() {
                pins[f][k] = gx[i as usize].to_array();
                if f > 0 {
                    gx[i as usize] = DVec3::ZERO;
                }
            }
        }
        walk.finish(m, &mut params)?;
        // The initial pinned positions: held from the start, every frame's pin.
        for (k, &i) in pinned.iter().enumerate() {
            gx[i as usize] = pins.iter().map(|p| DVec3::from(p[k])).sum();
        }
        Ok(Gradients {
            positions: gx.iter().map(|g| g.to_array()).collect(),
            velocities: gv.iter().map(|g| g.to_array()).collect(),
            params: PARAMS.iter().copied().zip(params).collect(),
            pinned,
            pins,
        })
    }
}

/// A frame's states and substeps: what a backward pass walks a recording with.
pub trait Walk {
    /// The inputs of the substeps of a frame that starts from `(x, v)`, in order (the
    /// frame's substeps recomputed).
    #[allow(clippy::type_complexity)]
    fn inputs(&mut self, model: &Model, x: &[DVec3], v: &[DVec3]) -> Result<Vec<(Vec<DVec3>, Vec<DVec3>)>, String>;
    /// The adjoint of the substep from `(x, v)` ([`Model::adjoint`]'s contract): `xb`,
    /// `vb` from the gradient with respect to its output to the one with respect to its
    /// input; the parameters' gradients added to `params` here or at [`Walk::finish`].
    fn adjoint(
        &mut self,
        model: &Model,
        x: &[DVec3],
        v: &[DVec3],
        xb: &mut [DVec3],
        vb: &mut [DVec3],
        params: &mut [f64],
    ) -> Result<(), String>;
    /// After the last substep: what it kept of the parameters' gradients added to `params`.
    fn finish(&mut self, _model: &Model, _params: &mut [f64]) -> Result<(), String> {
        Ok(())
    }
}

/// The f64 model's walk ([`Recording::backward`]).
pub struct ModelWalk;

impl Walk for ModelWalk {
    fn inputs(&mut self, m: &Model, x: &[DVec3], v: &[DVec3]) -> Result<Vec<(Vec<DVec3>, Vec<DVec3>)>, String> {
        let (mut x, mut v) = (x.to_vec(), v.to_vec());
        let mut path = Vec::with_capacity(m.substeps as usize);
        for _ in 0..m.substeps {
            path.push((x.clone(), v.clone()));
            m.substep(&mut x, &mut v);
        }
        Ok(path)
    }

    fn adjoint(
        &mut self,
        m: &Model,
        x: &[DVec3],
        v: &[DVec3],
        xb: &mut [DVec3],
        vb: &mut [DVec3],
        params: &mut [f64],
    ) -> Result<(), String> {
        m.adjoint(x, v, xb, vb, params);
        Ok(())
    }
}
