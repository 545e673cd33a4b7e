//! Simulation parameters: what a user may change, with units, defaults and one validation.
//!
//! # Why spring stiffness is given relative to the substep
//!
//! The cloth is integrated explicitly (Verlet). An explicit mass-spring system is stable
//! only while `ω·dt < 2` for its fastest mode, and for a particle held by springs of
//! stiffness `k_1 … k_m` that mode has `ω² ≲ 4·Σk / m` (a 1-D chain's highest mode is
//! `4k/m`; a 2-D grid with structural, shear and bend springs adds their projections).
//! A cloth of fixed size and mass has `m = M / n²` per particle, so a stiffness given in
//! N/m that is stable at n = 100 explodes at n = 1024 unless the substep shrinks tenfold.
//!
//! clothlab wants one fixed substep count for every grid size the app's slider offers
//! (10 … 1024), so each spring family's stiffness is a dimensionless fraction `κ` of the
//! stability limit: `k = κ · m / dt²` (N/m), and the damping likewise `c = ζ · m / dt`
//! (N·s/m). With `Σκ < 1` and `Σζ < 0.5` ([`SimParams::validate`] refuses anything else)
//! the integrator is stable at every `n` and `dt`. The price is that springs get softer
//! relative to gravity as `n` grows (the sag strain of a hanging column grows like
//! `n²·g·dt²/κ`), which is what Provot's strain limit is for: it holds every structural
//! and shear spring to at most `(1 + τ)` of its rest length whatever the springs do.
//! The defaults below were chosen by running 10 000 substeps at n = 64 … 1024
//! (`clothlab sim`), see `docs/parameters.md`.

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// A parameter that [`SimParams::validate`] or [`crate::Scene::validate`] refused.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("invalid parameter `{field}` = {value}: {reason}")]
pub struct ParamError {
    /// The field's name as written in the struct (and on the CLI); for a scene, its path
    /// in a scene file (`cloth.n`, `spheres[1].radius`).
    pub field: String,
    /// The refused value, formatted.
    pub value: String,
    /// What would be accepted.
    pub reason: String,
}

impl ParamError {
    pub(crate) fn new(field: impl Into<String>, value: impl std::fmt::Display, reason: impl Into<String>) -> Self {
        Self { field: field.into(), value: value.to_string(), reason: reason.into() }
    }
}

/// How the spring families' stiffness and damping are given.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum StiffnessUnits {
    /// Fractions of the explicit stability limit (`k = κ m / dt²`, `c = ζ m / dt`): stable
    /// at every n and dt, but the fabric softens as the grid gets finer.
    #[default]
    Fraction,
    /// A material: stretch and shear moduli (N/m) and a bending modulus (N·m), turned
    /// into spring constants by the grid spacing, so the same fabric at every n; the
    /// `*_damping` fields are then damping ratios (fractions of each spring's critical
    /// damping `2√(k m)`). Verlet refuses a dt it cannot integrate, naming the substeps.
    Physical,
}

/// How the cloth keeps clear of itself and of other cloths (`self_collision`).
///
/// In a scene file and in `--set` it is `"off"`, `"particles"` or `"triangles"`; `false`
/// and `true` stay accepted for off and particles (and are what those two are written
/// as, so that older files and outputs read the same).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SelfCollision {
    /// No contact between parts of the cloths.
    #[default]
    Off,
    /// Particles that are not neighbours keep `self_thickness` apart (a spatial hash
    /// rebuilt every substep; `core::cpu::self_collide`): the cheap rung, the thesis-era
    /// method. Surfaces stay apart only while the thickness is more than 0.71 spacing.
    Particles,
    /// Vertex–triangle and edge–edge contact between primitives that share no vertex,
    /// with each vertex's motion in a substep bounded so that no two primitives can pass
    /// through each other (`core::tri_contact`, docs/contact.md). The CPU solvers run it.
    Triangles,
}

impl SelfCollision {
    /// Every mode, in the order the app lists them.
    pub const ALL: [SelfCollision; 3] = [SelfCollision::Off, SelfCollision::Particles, SelfCollision::Triangles];

    /// The name in a scene file and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            SelfCollision::Off => "off",
            SelfCollision::Particles => "particles",
            SelfCollision::Triangles => "triangles",
        }
    }

    /// Whether the particle contact runs.
    pub fn particles(self) -> bool {
        self == SelfCollision::Particles
    }

    /// Whether the contact between triangles runs.
    pub fn triangles(self) -> bool {
        self == SelfCollision::Triangles
    }

    /// Whether either contact runs (the thickness is used).
    pub fn on(self) -> bool {
        self != SelfCollision::Off
    }
}

impl From<bool> for SelfCollision {
    fn from(on: bool) -> Self {
        if on { SelfCollision::Particles } else { SelfCollision::Off }
    }
}

impl Serialize for SelfCollision {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            SelfCollision::Off => s.serialize_bool(false),
            SelfCollision::Particles => s.serialize_bool(true),
            SelfCollision::Triangles => s.serialize_str("triangles"),
        }
    }
}

impl<'de> Deserialize<'de> for SelfCollision {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = SelfCollision;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("\"off\", \"particles\" or \"triangles\" (or false / true)")
            }
            fn visit_bool<E: serde::de::Error>(self, v: bool) -> Result<SelfCollision, E> {
                Ok(v.into())
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<SelfCollision, E> {
                SelfCollision::ALL.into_iter().find(|m| m.name() == v).ok_or_else(|| {
                    E::custom(format!("unknown self_collision `{v}`: expected \"off\", \"particles\" or \"triangles\""))
                })
            }
        }
        d.deserialize_any(Visitor)
    }
}

/// How a substep advances the particles (thesis §4.1.1–4.1.2). Every integrator keeps
/// the same state, positions and velocities (x, v) in f32, so the force kernels (which
/// read v) serve all of them unchanged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Integrator {
    /// Verlet (the thesis's program), `x' = x + (1 − damping)(x − x*) + a dt²`, run in
    /// velocity form: `v' = (1 − damping) v + a dt`, `x' = x + v' dt` (the same recurrence
    /// with `v = (x − x*)/dt`).
    #[default]
    Verlet,
    /// Explicit (forward) Euler: `x' = x + v dt`, `v' = v + a dt`. Order 1, unstable for
    /// any undamped oscillation: refused where the springs' damping cannot hold it.
    Euler,
    /// Symplectic (semi-implicit) Euler: `v' = v + a dt`, `x' = x + v' dt`. Order 1. In
    /// the (x, v) state it is Verlet's recurrence step for step (Verlet's kernels run it).
    SymplecticEuler,
    /// The midpoint method (RK2): two force evaluations per substep. Order 2.
    Rk2,
    /// Classical Runge–Kutta (RK4): four force evaluations per substep. Order 4.
    Rk4,
    /// Backward Euler with one Newton step (Baraff & Witkin 1998): `(M + dt D + dt² K) Δv
    /// = dt (f + dt ∂f/∂x v)`, solved by Jacobi-preconditioned conjugate gradients
    /// (`cg_iterations`). Order 1, stable at any dt.
    Implicit,
    /// Extended position-based dynamics (Macklin, Müller & Chentanez 2016): every spring a
    /// distance constraint of compliance `1/k`, solved by Gauss–Seidel over a colouring of
    /// the grid's springs (12 passes), `xpbd_iterations` times per substep with each
    /// spring's λ kept. Stable at any dt.
    Xpbd,
    /// Vertex Block Descent (Chen, Liu, Yang & Yuksel 2024): implicit Euler's energy
    /// minimised by sweeping vertex colours (`vbd_iterations` times per substep), each
    /// vertex a Newton step on its 3 × 3 block (core::cpu::vbd). Stable at any dt.
    Vbd,
}

impl Integrator {
    /// Every integrator, in the order the app lists them.
    pub const ALL: [Integrator; 8] = [
        Integrator::Verlet,
        Integrator::Euler,
        Integrator::SymplecticEuler,
        Integrator::Rk2,
        Integrator::Rk4,
        Integrator::Implicit,
        Integrator::Xpbd,
        Integrator::Vbd,
    ];

    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Verlet => "verlet",
            Integrator::Euler => "euler",
            Integrator::SymplecticEuler => "symplectic-euler",
            Integrator::Rk2 => "rk2",
            Integrator::Rk4 => "rk4",
            Integrator::Implicit => "implicit",
            Integrator::Xpbd => "xpbd",
            Integrator::Vbd => "vbd",
        }
    }

    /// What it is, in a few words (the command line's help lists them).
    pub fn summary(self) -> &'static str {
        match self {
            Integrator::Verlet => "the thesis's, default",
            Integrator::Euler => "explicit, order 1",
            Integrator::SymplecticEuler => "semi-implicit, order 1",
            Integrator::Rk2 => "the midpoint method",
            Integrator::Rk4 => "classical Runge–Kutta",
            Integrator::Implicit => "backward Euler, one Newton step by conjugate gradients",
            Integrator::Xpbd => "extended position-based dynamics",
            Integrator::Vbd => "Vertex Block Descent",
        }
    }

    /// The integrator named `s`.
    pub fn parse(s: &str) -> Option<Integrator> {
        Self::ALL.into_iter().find(|i| i.name() == s)
    }

    /// Whether it is explicit (bounded by a stability limit on dt).
    pub fn explicit(self) -> bool {
        !matches!(self, Integrator::Implicit | Integrator::Xpbd | Integrator::Vbd)
    }

    /// Whether `|amplification| ≤ 1` for the mode `s` (an eigenvalue of the linearised
    /// system, 1/s) at step `dt` with the per-substep velocity factor `keep = 1 − damping`.
    fn stable_mode(self, s: (f64, f64), dt: f64, keep: f64) -> bool {
        // z = s dt as a complex number; R(z) the method's amplification.
        let z = (s.0 * dt, s.1 * dt);
        let mul = |a: (f64, f64), b: (f64, f64)| (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
        let taylor = |order: usize| {
            // 1 + z + z²/2 + … + z^order/order!
            let (mut sum, mut term) = ((1.0, 0.0), (1.0, 0.0));
            for k in 1..=order {
                term = mul(term, z);
                term = (term.0 / k as f64, term.1 / k as f64);
                sum = (sum.0 + term.0, sum.1 + term.1);
            }
            sum
        };
        let r = match self {
            Integrator::Euler => taylor(1),
            Integrator::Rk2 => taylor(2),
            Integrator::Rk4 => taylor(4),
            // Verlet and symplectic Euler: the classical bound of `validate_for`.
            _ => return true,
        };
        (r.0 * r.0 + r.1 * r.1).sqrt() * keep <= 1.0 + 1e-9
    }
}

/// Every simulation parameter. Plain data: change fields, then call [`SimParams::validate`]
/// before handing it to a solver (solvers validate again and refuse bad values).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimParams {
    /// Simulated time per rendered frame, seconds. Default 1/60.
    pub frame_dt: f32,
    /// Substeps per frame; one substep advances `frame_dt / substeps` seconds. Default 16.
    pub substeps: u32,
    /// Gravity, m/s². Default (0, -9.81, 0).
    pub gravity: [f32; 3],
    /// Total mass of the cloth, kg, shared equally by its n² particles. Default 0.5.
    pub cloth_mass: f32,
    /// Linear air drag per unit mass, 1/s: each particle feels `-air_drag · m · v`. Default 0.1.
    pub air_drag: f32,
    /// Verlet velocity damping per substep, dimensionless in [0, 1):
    /// `v' = (1 - damping) v + a dt`. Default 0.0005.
    pub damping: f32,
    /// Structural spring stiffness (i±1, j±1) as a fraction of the explicit stability
    /// limit, dimensionless: `k = κ m / dt²`. Default 0.45.
    pub structural_stiffness: f32,
    /// Shear spring stiffness (diagonals), fraction of the stability limit. Default 0.15.
    pub shear_stiffness: f32,
    /// Bend spring stiffness (i±2, j±2), fraction of the stability limit. Default 0.05.
    pub bend_stiffness: f32,
    /// Structural spring damping, dimensionless: `c = ζ m / dt` (N·s/m). Default 0.04.
    pub structural_damping: f32,
    /// Shear spring damping, dimensionless (see `structural_damping`). Default 0.02.
    pub shear_damping: f32,
    /// Bend spring damping, dimensionless (see `structural_damping`). Default 0.01.
    pub bend_damping: f32,
    /// Provot strain limit τ: structural and shear springs are pulled back to at most
    /// `(1 + τ) · rest`, dimensionless. Default 0.10 (10 %).
    pub strain_limit: f32,
    /// Strain-limit passes (Jacobi) per substep, 0 switches it off. Default 1: with the
    /// tethers holding the cloth to its pins, a second pass lowered the worst strain at
    /// n = 256 only from 0.215 to 0.176 for a third of the substep's time.
    pub strain_iterations: u32,
    /// Tangential friction on the floor and on colliders, in [0, 1]: the fraction of the
    /// tangential motion removed at a contact. Default 0.4.
    pub friction: f32,
    /// Coulomb static friction coefficient μs, in 0 ..= 10: a contact whose tangential
    /// velocity relative to the surface is at most μs times the normal velocity it removes
    /// sticks. Either Coulomb coefficient above 0 switches the contacts from the share
    /// `friction` to Coulomb friction (`core::cpu::integrate::coulomb_contact`; VBD's
    /// smoothed Coulomb friction then takes `kinetic_friction` as its μ). Default 0.
    pub static_friction: f32,
    /// Coulomb kinetic friction coefficient μk, in 0 ..= `static_friction`: a sliding
    /// contact loses μk times the normal velocity it removes from its tangential velocity
    /// (a cloth sliding on a floor slows at μk·g). Default 0.
    pub kinetic_friction: f32,
    /// Distance kept between the cloth and every collider (its thickness), m. Default 0.01.
    pub collision_margin: f32,
    /// Wind velocity, m/s. Default (0, 0, 0): no wind.
    pub wind: [f32; 3],
    /// How stiffness and damping are given. Default [`StiffnessUnits::Fraction`].
    pub stiffness_units: StiffnessUnits,
    /// `stiffness_units = physical`: in-plane stretch modulus, N/m (the structural
    /// springs' k: a square lattice's axial springs of constant k have a 2-D Young's
    /// modulus of k). Default 50.6: what the fraction defaults give at n = 64.
    pub stretch_modulus: f32,
    /// `stiffness_units = physical`: in-plane shear modulus, N/m (the shear springs' k).
    /// Default 16.9.
    pub shear_modulus: f32,
    /// `stiffness_units = physical`: bending modulus, N·m; a bend spring over two
    /// spacings h gets `k = B / h²`. Default 5.67e-3.
    pub bend_modulus: f32,
    /// Wind pressure coefficient, kg/(m²·s): a triangle of area A and unit normal n̂ feels
    /// `wind_coefficient · A · (n̂·w) n̂`, shared by its three corners. Default 0.5.
    pub wind_coefficient: f32,
    /// How a substep integrates. Default [`Integrator::Verlet`].
    pub integrator: Integrator,
    /// `integrator = implicit`: conjugate-gradient iterations per substep, 1 ..= 256.
    /// Default 16.
    pub cg_iterations: u32,
    /// `integrator = xpbd`: Gauss–Seidel iterations (of 12 passes each) per substep, with
    /// each spring's λ kept across them, 1 ..= 64. Default 1.
    pub xpbd_iterations: u32,
    /// `integrator = vbd`: sweeps over the vertex colours per substep, 1 ..= 64. Default 8.
    pub vbd_iterations: u32,
    /// `integrator = vbd`: the spectral radius estimate ρ of the paper's Chebyshev
    /// acceleration, in [0, 1): after sweep k every displacement is over-relaxed,
    /// `D ← ω_k (D − D⁽ᵏ⁻²⁾) + D⁽ᵏ⁻²⁾` with `ω₁ = 1`, `ω₂ = 2/(2 − ρ²)`,
    /// `ω_k = 4/(4 − ρ² ω_{k−1})`. 0 switches it off. Default 0.
    pub vbd_rho: f32,
    /// Contact of the cloths with themselves and each other: [`SelfCollision`] (off,
    /// particles, triangles). Default off.
    pub self_collision: SelfCollision,
    /// The cloth's thickness for self-collision, m, in 0.001 ..= 0.5 (the triangles'
    /// contact: from 0.1 of the spacing up). Default 0.02.
    pub self_thickness: f32,
    /// `self_collision = triangles`: how far beyond a substep's reach the search for
    /// pairs looks, in rest spacings, in 0 ..= 4. Its pairs then serve the substeps after
    /// it until some vertex has moved (from the cloths' mean motion) half that far; the
    /// pairs each substep acts on, and so the results, are the same whatever the margin
    /// (docs/contact.md). 0 searches every substep. Default 0.5.
    pub search_margin: f32,
}

impl Default for SimParams {
    fn default() -> Self {
        Self {
            frame_dt: 1.0 / 60.0,
            substeps: 16,
            gravity: [0.0, -9.81, 0.0],
            cloth_mass: 0.5,
            air_drag: 0.1,
            damping: 0.0005,
            structural_stiffness: 0.45,
            shear_stiffness: 0.15,
            bend_stiffness: 0.05,
            structural_damping: 0.04,
            shear_damping: 0.02,
            bend_damping: 0.01,
            strain_limit: 0.10,
            strain_iterations: 1,
            friction: 0.4,
            static_friction: 0.0,
            kinetic_friction: 0.0,
            collision_margin: 0.01,
            wind: [0.0; 3],
            wind_coefficient: 0.5,
            stiffness_units: StiffnessUnits::Fraction,
            stretch_modulus: 50.6,
            shear_modulus: 16.9,
            bend_modulus: 5.67e-3,
            integrator: Integrator::Verlet,
            cg_iterations: 16,
            xpbd_iterations: 1,
            vbd_iterations: 8,
            vbd_rho: 0.0,
            self_collision: SelfCollision::Off,
            self_thickness: 0.02,
            search_margin: 0.5,
        }
    }
}

/// The contact between triangles' thickness is below this fraction of the closest rest
/// distance between primitives that share no vertex (a grid's: the spacing over √2), so that
/// a cloth at rest does not push itself apart.
pub const TRIANGLE_THICKNESS_FRACTION: f32 = 0.9;

/// Upper bound on substeps per frame (a frame of more would never be interactive).
pub const MAX_SUBSTEPS: u32 = 1024;

/// Upper bound on conjugate-gradient iterations per implicit substep.
pub const MAX_CG_ITERATIONS: u32 = 256;
/// Upper bound on strain-limit passes per substep.
pub const MAX_STRAIN_ITERATIONS: u32 = 64;

impl SimParams {
    /// These parameters with soft springs and heavy damping (Σζ > Σκ in fractions of the
    /// stability limit): a fabric every integrator runs at the default substeps, explicit
    /// Euler and the midpoint method included — the common ground of the integrator
    /// tests (engine/tests/suite/integrators.rs, tests/tests/suite/integrators.rs, free_fall.rs).
    pub fn with_soft_springs(self) -> SimParams {
        SimParams {
            structural_stiffness: 0.1,
            shear_stiffness: 0.03,
            bend_stiffness: 0.01,
            structural_damping: 0.2,
            shear_damping: 0.1,
            bend_damping: 0.05,
            ..self
        }
    }

    /// Self-collision on a mesh of `particles` whose closest two particles that share no
    /// spring lie `closest_unsprung` apart at rest: at most what the hash's words hold, and
    /// a thickness below half that distance (a pair closer than twice the thickness at
    /// rest would push apart while the cloth lies still).
    pub fn check_mesh(&self, particles: usize, closest_unsprung: f32) -> Result<(), ParamError> {
        if !self.self_collision.particles() {
            return Ok(());
        }
        let max = crate::tables::SELF_COLLISION_MAX_PARTICLES;
        if particles > max {
            return Err(ParamError::new(
                "self_collision",
                "particles",
                format!(
                    "a mesh of {particles} particles is too large for self-collision (its hash holds {max} at most)"
                ),
            ));
        }
        // A grid leaves out the pairs within twice the thickness at rest; a mesh's
        // neighbours are its springs, so two particles that share none must start apart.
        if 2.0 * self.self_thickness >= closest_unsprung {
            return Err(ParamError::new(
                "self_thickness",
                self.self_thickness,
                format!(
                    "two particles of this mesh that share no spring lie {closest_unsprung:.4} m apart at rest, within twice the thickness: \
                     they would push each other apart; use less than {:.4} m",
                    0.5 * closest_unsprung
                ),
            ));
        }
        Ok(())
    }

    /// The contact between triangles on a cloth whose closest primitives that share no
    /// vertex lie `closest` apart at rest (`what` names them in a refusal: "this mesh's"):
    /// a thickness below [`TRIANGLE_THICKNESS_FRACTION`] of that.
    pub fn check_triangles(&self, closest: f32, what: &str) -> Result<(), ParamError> {
        let max = TRIANGLE_THICKNESS_FRACTION * closest;
        if self.self_collision.triangles() && self.self_thickness >= max {
            return Err(ParamError::new(
                "self_thickness",
                self.self_thickness,
                format!(
                    "{what} closest vertex and triangle (or two edges) that share no vertex lie {closest:.4} m apart at rest: \
                     the contact between triangles takes a thickness under {max:.4} m ({TRIANGLE_THICKNESS_FRACTION} of that), \
                     or a cloth at rest would push itself apart"
                ),
            ));
        }
        Ok(())
    }

    /// Duration of one substep, seconds.
    pub fn dt(&self) -> f32 {
        self.frame_dt / self.substeps as f32
    }

    /// Mass of one particle for an `n × n` cloth, kg.
    pub fn particle_mass(&self, n: u32) -> f32 {
        self.cloth_mass / (n as f32 * n as f32)
    }

    /// Spring stiffness in N/m for a family with fraction `kappa` on an `n × n` cloth.
    pub fn stiffness_n_per_m(&self, kappa: f32, n: u32) -> f32 {
        kappa * self.particle_mass(n) / (self.dt() * self.dt())
    }

    /// Spring damping in N·s/m for a family with fraction `zeta` on an `n × n` cloth.
    pub fn damping_ns_per_m(&self, zeta: f32, n: u32) -> f32 {
        zeta * self.particle_mass(n) / self.dt()
    }

    /// (k N/m, c N·s/m) of the structural, shear and bend springs of an `n × n` cloth with
    /// grid spacing `spacing` m, in either unit system.
    pub fn spring_constants(&self, n: u32, spacing: f32) -> [(f32, f32); 3] {
        self.spring_constants_for_mass(self.particle_mass(n), spacing)
    }

    /// [`SimParams::spring_constants`] for springs between particles of mass `m` kg (a
    /// mesh's spring takes its lighter end's mass) at mean spacing `spacing` m.
    pub fn spring_constants_for_mass(&self, m: f32, spacing: f32) -> [(f32, f32); 3] {
        let families = [
            (self.structural_stiffness, self.structural_damping, self.stretch_modulus),
            (self.shear_stiffness, self.shear_damping, self.shear_modulus),
            (self.bend_stiffness, self.bend_damping, self.bend_modulus / (spacing * spacing).max(1e-12)),
        ];
        let dt = self.dt();
        families.map(|(kappa, zeta, k_physical)| match self.stiffness_units {
            StiffnessUnits::Fraction => (kappa * m / (dt * dt), zeta * m / dt),
            StiffnessUnits::Physical => (k_physical, zeta * 2.0 * (k_physical * m).sqrt()),
        })
    }

    /// [`SimParams::validate`], and whether the integrator can integrate the springs of
    /// an `n × n` cloth of spacing `spacing` at this dt. Verlet and symplectic Euler: the
    /// springs' fraction of the stability limit `Σk·dt²/m` must stay under 0.95 and the
    /// damping's `Σc·dt/m` under 0.5 (the bounds the fraction mode enforces). Euler, RK2
    /// and RK4: every mode of the grid, `s² + (μ·4Σc/m + drag)s + μ·4Σk/m = 0` for
    /// μ ∈ (0, 1], must have an amplification of at most 1. `implicit` and `xpbd` are
    /// stable at any dt. A refusal names the substeps that would do.
    /// With self-collision, the thickness is bounded by the grid's spacing
    /// ([`SimParams::check_grid`]).
    pub fn validate_for(&self, n: u32, spacing: f32) -> Result<(), ParamError> {
        self.validate_for_mass(self.particle_mass(n), spacing, &format!("at n = {n}"))?;
        self.check_grid(n, spacing)
    }

    /// The largest self-collision thickness a grid of spacing `spacing` takes: 1.5
    /// spacings, half the rest distance of the closest pairs it may push apart (three
    /// spacings: outside the springs' 5 × 5 stencil), as a mesh's is half its closest
    /// pair that shares no spring. It also bounds the pair search's cost: a cell of side t
    /// holds about (t/h)² particles of a flat cloth, and every particle reads the cells
    /// around its own, so a thickness of the cloth's size would make a substep's cost
    /// grow with the square of the particles (n = 512 with t = 0.5 m: 5 substeps took over
    /// 100 s).
    pub fn max_grid_thickness(spacing: f32) -> f32 {
        1.5 * spacing
    }

    /// The largest thickness `mode` takes on a grid of spacing `spacing` (0 when off): the
    /// particle contact's [`SimParams::max_grid_thickness`], or just under the contact
    /// between triangles' [`TRIANGLE_THICKNESS_FRACTION`] of the spacing over √2.
    pub fn max_thickness_on_grid(mode: SelfCollision, spacing: f32) -> f32 {
        match mode {
            SelfCollision::Off => 0.0,
            SelfCollision::Particles => Self::max_grid_thickness(spacing),
            SelfCollision::Triangles => 0.999 * TRIANGLE_THICKNESS_FRACTION * spacing * std::f32::consts::FRAC_1_SQRT_2,
        }
    }

    /// Self-collision on an `n × n` grid of spacing `spacing`: a thickness of at most
    /// [`SimParams::max_grid_thickness`].
    pub fn check_grid(&self, n: u32, spacing: f32) -> Result<(), ParamError> {
        self.check_triangles(spacing * std::f32::consts::FRAC_1_SQRT_2, &format!("at n = {n} the grid's"))?;
        let max = Self::max_grid_thickness(spacing);
        if self.self_collision.particles() && self.self_thickness > max {
            return Err(ParamError::new(
                "self_thickness",
                self.self_thickness,
                format!(
                    "at n = {n} the grid's spacing is {spacing:.4} m: self-collision takes a thickness of at most 1.5 spacings ({max:.4} m), \
                     half the distance of the closest pairs it keeps apart (a thicker one fills every cell of the pair search \
                     with particles of the flat cloth); use at most {max:.4} m or a coarser grid"
                ),
            ));
        }
        Ok(())
    }

    /// [`SimParams::validate_for`] for particles of mass `m` (a mesh: its lightest
    /// particle) at spacing `spacing`; `what` names the cloth in a refusal ("at n = 64").
    pub fn validate_for_mass(&self, m: f32, spacing: f32, what: &str) -> Result<(), ParamError> {
        self.validate()?;
        let explicit = self.integrator.explicit();
        let classical = matches!(self.integrator, Integrator::Verlet | Integrator::SymplecticEuler);
        if !explicit || (classical && self.stiffness_units == StiffnessUnits::Fraction) {
            return Ok(());
        }
        let consts = self.spring_constants_for_mass(m, spacing);
        let k: f32 = consts.iter().map(|c| c.0).sum();
        let c: f32 = consts.iter().map(|c| c.1).sum();
        let dt = self.dt();
        let name = self.integrator.name();
        let dt_max = if classical {
            // Largest stable dt: k dt²/m < 0.95 and c dt/m < 0.5.
            (0.95 * m / k.max(1e-30)).sqrt().min(0.5 * m / c.max(1e-30))
        } else {
            let stable = |dt: f64| self.modes_stable(dt, m, k, c);
            if stable(dt as f64) {
                return Ok(());
            }
            if self.stiffness_units == StiffnessUnits::Fraction {
                // k = κ m/dt², c = ζ m/dt: every dt gives the same modes in units of dt.
                return Err(ParamError::new(
                    "integrator",
                    name,
                    format!(
                        "{name} cannot integrate springs given as fractions of the stability limit (Σκ = {:.2}, Σζ = {:.2}): some mode grows at every dt — use verlet, symplectic-euler, rk4, implicit or xpbd, much softer springs (Euler needs Σζ > Σκ), or stiffness_units = physical",
                        self.structural_stiffness + self.shear_stiffness + self.bend_stiffness,
                        self.structural_damping + self.shear_damping + self.bend_damping
                    ),
                ));
            }
            // Bisection for the largest stable dt below this one.
            let (mut lo, mut hi) = (0.0f64, dt as f64);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if stable(mid) { lo = mid } else { hi = mid }
            }
            lo as f32
        };
        if dt >= dt_max {
            let need = (self.frame_dt as f64 / dt_max.max(1e-30) as f64).floor() as u64 + 1;
            let units = match self.stiffness_units {
                StiffnessUnits::Fraction => "fraction",
                StiffnessUnits::Physical => "physical",
            };
            let fix = if need > MAX_SUBSTEPS as u64 {
                format!(
                    "and no count up to {MAX_SUBSTEPS} substeps per frame does: use integrator = implicit or xpbd, a coarser grid, or softer moduli"
                )
            } else {
                format!(
                    "use substeps ≥ {need} (at frame_dt {}), a coarser grid, softer moduli, or integrator = implicit or xpbd",
                    self.frame_dt
                )
            };
            return Err(ParamError::new(
                "substeps",
                self.substeps,
                format!(
                    "stiffness_units = {units} {what}: particles of {m:.3e} kg held by springs of Σk = {k:.1} N/m are stable with {name} only for dt < {dt_max:.3e} s; this dt is {dt:.3e} s — {fix}"
                ),
            ));
        }
        Ok(())
    }

    /// Whether every mode of the grid is stable with the integrator at step `dt` (see
    /// [`SimParams::validate_for`]): particles of mass `m` held by springs of total
    /// stiffness `k` and damping `c`.
    fn modes_stable(&self, dt: f64, m: f32, k: f32, c: f32) -> bool {
        let (a, b, drag) = (4.0 * k as f64 / m as f64, 4.0 * c as f64 / m as f64, self.air_drag as f64);
        let keep = 1.0 - self.damping as f64;
        (1..=256).all(|q| {
            let mu = q as f64 / 256.0;
            let (bb, aa) = (mu * b + drag, mu * a);
            let disc = bb * bb - 4.0 * aa;
            let roots = if disc >= 0.0 {
                [(0.5 * (-bb + disc.sqrt()), 0.0), (0.5 * (-bb - disc.sqrt()), 0.0)]
            } else {
                [(-0.5 * bb, 0.5 * (-disc).sqrt()), (-0.5 * bb, -0.5 * (-disc).sqrt())]
            };
            roots.iter().all(|&s| self.integrator.stable_mode(s, dt, keep))
        })
    }

    /// Whether contacts take Coulomb friction (either coefficient above 0) instead of the
    /// share `friction` (`StepParams::coulomb`): between cloths too, where self-collision
    /// is on.
    pub fn coulomb(&self) -> bool {
        self.static_friction > 0.0 || self.kinetic_friction > 0.0
    }

    /// Checks every field; the first bad one is reported. Nothing that passes can make a
    /// solver produce NaN from a valid scene.
    pub fn validate(&self) -> Result<(), ParamError> {
        finite_in("frame_dt", self.frame_dt, 1e-5, 1.0)?;
        if self.substeps == 0 || self.substeps > MAX_SUBSTEPS {
            return Err(ParamError::new("substeps", self.substeps, format!("must be in 1 ..= {MAX_SUBSTEPS}")));
        }
        for (i, g) in self.gravity.iter().enumerate() {
            finite_in(["gravity.x", "gravity.y", "gravity.z"][i], *g, -1000.0, 1000.0)?;
        }
        finite_in("cloth_mass", self.cloth_mass, 1e-6, 1e6)?;
        if self.cloth_mass <= 0.0 {
            return Err(ParamError::new("cloth_mass", self.cloth_mass, "must be > 0"));
        }
        // Explicit drag is stable while air_drag · dt < 1; keep a wide margin.
        finite_in("air_drag", self.air_drag, 0.0, 0.5 / self.dt())?;
        finite_in("damping", self.damping, 0.0, 0.5)?;
        finite_in("structural_stiffness", self.structural_stiffness, 0.0, 1.0)?;
        finite_in("shear_stiffness", self.shear_stiffness, 0.0, 1.0)?;
        finite_in("bend_stiffness", self.bend_stiffness, 0.0, 1.0)?;
        let kappa = self.structural_stiffness + self.shear_stiffness + self.bend_stiffness;
        if kappa >= 0.95 {
            return Err(ParamError::new(
                "structural_stiffness + shear_stiffness + bend_stiffness",
                kappa,
                "must be < 0.95 (fractions of the explicit stability limit, see docs/parameters.md)",
            ));
        }
        finite_in("structural_damping", self.structural_damping, 0.0, 0.5)?;
        finite_in("shear_damping", self.shear_damping, 0.0, 0.5)?;
        finite_in("bend_damping", self.bend_damping, 0.0, 0.5)?;
        let zeta = self.structural_damping + self.shear_damping + self.bend_damping;
        if zeta >= 0.5 {
            return Err(ParamError::new(
                "structural_damping + shear_damping + bend_damping",
                zeta,
                "must be < 0.5 (explicit damping is unstable beyond)",
            ));
        }
        finite_in("strain_limit", self.strain_limit, 0.0, 10.0)?;
        if self.strain_iterations > MAX_STRAIN_ITERATIONS {
            return Err(ParamError::new(
                "strain_iterations",
                self.strain_iterations,
                format!("must be in 0 ..= {MAX_STRAIN_ITERATIONS}"),
            ));
        }
        finite_in("friction", self.friction, 0.0, 1.0)?;
        finite_in("static_friction", self.static_friction, 0.0, 10.0)?;
        finite_in("kinetic_friction", self.kinetic_friction, 0.0, 10.0)?;
        if self.kinetic_friction > self.static_friction {
            return Err(ParamError::new(
                "kinetic_friction",
                self.kinetic_friction,
                format!("must be ≤ static_friction ({}): Coulomb's μk ≤ μs, give both", self.static_friction),
            ));
        }
        finite_in("collision_margin", self.collision_margin, 0.0, 1.0)?;
        for (i, w) in self.wind.iter().enumerate() {
            finite_in(["wind.x", "wind.y", "wind.z"][i], *w, -1000.0, 1000.0)?;
        }
        finite_in("wind_coefficient", self.wind_coefficient, 0.0, 1000.0)?;
        finite_in("stretch_modulus", self.stretch_modulus, 0.0, 1e9)?;
        finite_in("shear_modulus", self.shear_modulus, 0.0, 1e9)?;
        finite_in("bend_modulus", self.bend_modulus, 0.0, 1e6)?;
        if self.xpbd_iterations == 0 || self.xpbd_iterations > 64 {
            return Err(ParamError::new("xpbd_iterations", self.xpbd_iterations, "must be in 1 ..= 64"));
        }
        if self.vbd_iterations == 0 || self.vbd_iterations > 64 {
            return Err(ParamError::new("vbd_iterations", self.vbd_iterations, "must be in 1 ..= 64"));
        }
        if !(self.vbd_rho.is_finite() && (0.0..1.0).contains(&self.vbd_rho)) {
            return Err(ParamError::new("vbd_rho", self.vbd_rho, "must be in 0 ..< 1 (0: no acceleration)"));
        }
        finite_in("self_thickness", self.self_thickness, 1e-3, 0.5)?;
        finite_in("search_margin", self.search_margin, 0.0, 4.0)?;
        if self.cg_iterations == 0 || self.cg_iterations > MAX_CG_ITERATIONS {
            return Err(ParamError::new(
                "cg_iterations",
                self.cg_iterations,
                format!("must be in 1 ..= {MAX_CG_ITERATIONS}"),
            ));
        }
        Ok(())
    }
}

/// Refuses NaN, infinities and values outside `[lo, hi]`.
pub(crate) fn finite_in(field: impl Into<String>, v: f32, lo: f32, hi: f32) -> Result<(), ParamError> {
    if !v.is_finite() {
        return Err(ParamError::new(field, v, "must be a finite number"));
    }
    if v < lo || v > hi {
        return Err(ParamError::new(field, v, format!("must be in {lo} ..= {hi}")));
    }
    Ok(())
}

/// The values of parameter `name` one per world, where `value` gives them so: a list where
/// the parameter takes a number or a word (`damping = [0.0, 0.01]`), a list of lists where
/// it takes a list (`wind = [[1, 0, 0], [2, 0, 0]]`); `None` where `value` is one value
/// for every world, or `name` is not a parameter. The one rule the command line's `--set`
/// and a scene file's `[params]` follow.
pub fn per_world(name: &str, value: &serde_json::Value) -> Option<Vec<serde_json::Value>> {
    let shape = serde_json::to_value(SimParams::default()).ok()?;
    let slot = shape.get(name)?;
    let list = value.as_array()?;
    let per = if slot.is_array() { !list.is_empty() && list.iter().all(|v| v.is_array()) } else { true };
    per.then(|| list.clone())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_validate() {
        assert_eq!(SimParams::default().validate(), Ok(()));
    }

    #[test]
    fn physical_stiffness_is_the_same_at_every_n_and_verlet_names_the_substeps_it_needs() {
        let p = SimParams { stiffness_units: StiffnessUnits::Physical, ..Default::default() };
        let h = |n: u32| 2.0 / (n - 1) as f32;
        // The structural and shear k are the moduli whatever n; bend k = B / h².
        for n in [64, 512] {
            let c = p.spring_constants(n, h(n));
            assert_eq!((c[0].0, c[1].0), (50.6, 16.9));
            assert!((c[2].0 - 5.67e-3 / (h(n) * h(n))).abs() <= 1e-3 * c[2].0, "{c:?}");
        }
        // At n = 64 they reproduce the fraction defaults (κ 0.45, 0.15, 0.05 of m/dt²)
        // within 1 %.
        let f = SimParams::default().spring_constants(64, h(64));
        let q = p.spring_constants(64, h(64));
        for k in 0..3 {
            assert!((q[k].0 / f[k].0 - 1.0).abs() < 0.01, "{k}: {q:?} vs {f:?}");
        }
        assert_eq!(p.validate_for(64, h(64)), Ok(()));
        // At n = 128, Verlet needs 30 substeps per frame (dt < 5.7e-4 s): it names them,
        // and that many pass.
        let need = |e: ParamError| -> u32 {
            e.reason.split("substeps ≥ ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap()
        };
        let e = p.validate_for(128, h(128)).unwrap_err();
        let k = need(e.clone());
        assert!((25..35).contains(&k), "{e}");
        assert_eq!(SimParams { substeps: k, ..p.clone() }.validate_for(128, h(128)), Ok(()));
        assert!(SimParams { substeps: k - 1, ..p.clone() }.validate_for(128, h(128)).is_err());
        // At n = 512 the bend springs (k = B/h² ≈ 370 N/m, Σk ≈ 438 N/m) on particles of
        // 1.9e-6 kg need dt < 6.4e-5 s: 260 substeps per frame, which the state in (x, v)
        // integrates (the old prev-based state lost the motion beyond 75).
        let k = need(p.validate_for(512, h(512)).unwrap_err());
        assert!((250..275).contains(&k), "{k}");
        assert_eq!(SimParams { substeps: k, ..p.clone() }.validate_for(512, h(512)), Ok(()));
        // At n = 2048 no count up to 1024 does, and the refusal says so and names implicit.
        let e = p.validate_for(2048, 2.0 / 2047.0).unwrap_err();
        assert!(e.reason.contains("no count up to 1024") && e.reason.contains("implicit"), "{e}");
        let implicit = SimParams { integrator: Integrator::Implicit, ..p };
        assert_eq!(implicit.validate_for(512, h(512)), Ok(()));
    }

    #[test]
    fn refuses_nan_negative_and_unstable() {
        let bad = [
            SimParams { frame_dt: f32::NAN, ..Default::default() },
            SimParams { cloth_mass: -1.0, ..Default::default() },
            SimParams { substeps: 0, ..Default::default() },
            SimParams { damping: -0.1, ..Default::default() },
            SimParams { wind: [f32::INFINITY, 0.0, 0.0], ..Default::default() },
            SimParams { structural_stiffness: 0.9, shear_stiffness: 0.1, ..Default::default() },
            SimParams { strain_iterations: 1000, ..Default::default() },
        ];
        for p in bad {
            assert!(p.validate().is_err(), "{p:?} should be refused");
        }
    }
}
