//! Vertex Block Descent (Chen, Liu, Yang & Yuksel, "Vertex Block Descent", ACM TOG 43(4),
//! 2024) for the mass-spring cloth: the CPU reference of issue 46's integrator, not yet an
//! [`crate::Integrator`] (no backend runs it; the GPU kernels and the solvers' wiring come
//! next, with contacts as penalty energies and the accelerated variant).
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
//! The new velocity is the substep's displacement over h, `v = D/h`. D is kept as a sum of
//! small terms (`h v + h² g` and each step) instead of being taken back as `x − x⁰`: in f32
//! that difference rounds `h² g` to a few ulps of x and biased every integrator of this
//! crate by up to 7.5 % in free fall before the state kept velocities (see
//! `integrators.rs`); with no spring stretched VBD is then exactly implicit Euler's
//! recurrence.

use glam::{Mat3, Vec3};

use super::{mass, v3, v4};
use crate::grid::{ClothTopology, StepParams, V4};

/// The vertex colours of `topo`: lists of particles, no two of one list joined by a spring.
/// A grid: the 9 classes of `(i mod 3, j mod 3)` (its 12-slot stencil reaches 2 away, so
/// two particles of one class, 3 apart or more, share none). A mesh: greedy over its rows
/// in particle order (each particle the smallest colour none of its springs' other ends
/// has), as many colours as that takes (a fan's centre of valence 64 apart, a few more
/// than the largest row of a mesh's lattice).
pub fn colouring(topo: &ClothTopology) -> Vec<Vec<u32>> {
    let np = topo.num_particles();
    let mut colour_of = vec![u32::MAX; np];
    if topo.mesh.is_none() && topo.n >= 3 {
        let n = topo.n as usize;
        for (k, c) in colour_of.iter_mut().enumerate() {
            *c = ((k % n) % 3 + 3 * ((k / n) % 3)) as u32;
        }
    } else {
        let mut used = Vec::new();
        for i in 0..np {
            used.clear();
            used.extend(topo.slots.row(i).iter().filter_map(|s| s.other()).map(|j| colour_of[j]));
            colour_of[i] = (0..).find(|c| !used.contains(c)).unwrap_or(0);
        }
    }
    let count = colour_of.iter().copied().max().map_or(0, |c| c as usize + 1);
    let mut colours = vec![Vec::new(); count];
    for (k, &c) in colour_of.iter().enumerate() {
        colours[c as usize].push(k as u32);
    }
    colours.retain(|c| !c.is_empty());
    colours
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

/// One VBD substep of `iterations` sweeps over `colours` ([`colouring`]), `pos` and `vel`
/// in place. Gravity only as the external force (no drag, wind or contacts yet); pinned
/// particles (`w = 0`) and the grabbed one stay where they are, at rest.
pub fn vbd_substep(
    p: &StepParams,
    topo: &ClothTopology,
    colours: &[Vec<u32>],
    iterations: u32,
    pos: &mut [V4],
    vel: &mut [V4],
) {
    let h = p.dt;
    let g = v3(p.gravity);
    let start: Vec<Vec3> = pos.iter().map(|&x| v3(x)).collect();
    let still: Vec<bool> = (0..pos.len()).map(|i| pos[i][3] == 0.0 || i as i32 == p.grab_index).collect();
    let held = |i: usize| still[i];
    // The displacement over the substep, started at the inertial prediction y − x⁰.
    let mut disp: Vec<Vec3> =
        (0..pos.len()).map(|i| if held(i) { Vec3::ZERO } else { h * v3(vel[i]) + (h * h) * g }).collect();
    let y: Vec<Vec3> = start.iter().zip(&disp).map(|(x, d)| *x + *d).collect();
    let m: Vec<f32> = pos.iter().map(|x| mass(p, x[3])).collect();
    let mut x = y.clone();
    for _ in 0..iterations {
        for colour in colours {
            for &i in colour {
                let i = i as usize;
                if held(i) {
                    continue;
                }
                let step = block_step(topo, i, m[i] / (h * h), &x, &y, &start, h);
                x[i] += step;
                disp[i] += step;
            }
        }
    }
    for (i, (p4, v4_)) in pos.iter_mut().zip(vel.iter_mut()).enumerate() {
        if held(i) {
            *v4_ = [0.0, 0.0, 0.0, v4_[3]];
            continue;
        }
        *p4 = v4(start[i] + disp[i], p4[3]);
        *v4_ = v4(disp[i] * (1.0 / h), v4_[3]);
    }
}

/// Vertex `i`'s Newton step on its block (`inertia` = mᵢ/h²): `Hᵢ⁻¹ fᵢ` at `x` (the
/// others' newest positions), zero where the block cannot be solved (not positive definite
/// in f32).
fn block_step(topo: &ClothTopology, i: usize, inertia: f32, x: &[Vec3], y: &[Vec3], start: &[Vec3], h: f32) -> Vec3 {
    let mut f = -inertia * (x[i] - y[i]);
    let mut hess = Mat3::from_diagonal(Vec3::splat(inertia));
    for s in topo.slots.row(i) {
        let Some(j) = s.other() else { continue };
        let d = x[i] - x[j];
        let l = d.length();
        if l <= f32::MIN_POSITIVE || s.ks <= 0.0 {
            continue;
        }
        let n = d * (1.0 / l);
        let nn = Mat3::from_cols(n * n.x, n * n.y, n * n.z);
        let tangent = (1.0 - s.rest / l).max(0.0);
        let hs = s.ks * nn + (s.ks * tangent) * (Mat3::IDENTITY - nn);
        f -= s.ks * (l - s.rest) * n;
        if s.kd > 0.0 {
            // Rayleigh damping of the spring (D = kd/ks · its Hessian) on the two ends'
            // relative displacement this substep, the other end held.
            let c = s.kd / (s.ks * h);
            f -= c * (hs * ((x[i] - start[i]) - (x[j] - start[j])));
            hess += c * hs;
        }
        hess += hs;
    }
    let det = hess.determinant();
    if !(det.is_finite() && det > 0.0) {
        return Vec3::ZERO;
    }
    hess.inverse() * f
}
