//! The order of a substep, written once: the [`Stage`]s each integrator and switch runs,
//! in order. Two paths follow it — the engine's recipes (`clothlab_engine::recipe`: each
//! stage as the variant's kernels, fused as its switches say) and the CPU solver's
//! kernel-by-kernel path (`clothlab_cpu::CpuSolver`: each stage as its twins, on SIMD
//! rows where the grid allows). The fused SIMD sweep (`cpu::fused`) is the CPU's fast
//! path for Verlet on a grid and is tested to give this order's bits.

use crate::params::{Integrator, SimParams};

/// How a substep integrates: the integrator with its iteration counts and the switches
/// that add stages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Integration {
    /// The integrator.
    pub integrator: Integrator,
    /// Conjugate-gradient iterations (`implicit` only).
    pub cg_iterations: u32,
    /// Gauss–Seidel iterations (`xpbd` only).
    pub xpbd_iterations: u32,
    /// Sweeps over the vertex colours (`vbd` only).
    pub vbd_iterations: u32,
    /// The Chebyshev ρ of `vbd` as f32 bits (0: no acceleration).
    pub vbd_rho_bits: u32,
    /// The particle contact after the strain limit (core::cpu::self_collide).
    pub self_collision: bool,
    /// The contact between triangles (core::tri_contact::Contact): bounds at the start,
    /// the separation before the colliders, the clamp after the strain limit.
    pub triangles: bool,
    /// Its contacts with Coulomb friction (the parameters have Coulomb's coefficients:
    /// the `_friction` response kernels).
    pub self_friction: bool,
    /// Substeps per frame (what temporal blocking may fold into one dispatch).
    pub substeps: u32,
}

impl Integration {
    /// Verlet, the thesis's.
    pub const VERLET: Integration = Integration {
        integrator: Integrator::Verlet,
        cg_iterations: 0,
        xpbd_iterations: 0,
        vbd_iterations: 0,
        vbd_rho_bits: 0,
        self_collision: false,
        triangles: false,
        self_friction: false,
        substeps: 1,
    };

    /// What `params` ask for.
    pub fn of(params: &SimParams) -> Self {
        Self {
            integrator: params.integrator,
            cg_iterations: params.cg_iterations,
            xpbd_iterations: params.xpbd_iterations,
            vbd_iterations: params.vbd_iterations,
            vbd_rho_bits: params.vbd_rho.to_bits(),
            self_collision: params.self_collision.particles(),
            triangles: params.self_collision.triangles(),
            self_friction: params.self_collision.particles() && params.coulomb(),
            substeps: params.substeps,
        }
    }

    /// VBD's Chebyshev ρ (0: no acceleration).
    pub fn vbd_rho(&self) -> f32 {
        f32::from_bits(self.vbd_rho_bits)
    }

    /// The stages of one substep with `strain_passes` strain passes, in order: the
    /// integrator's (see [`Stage`]), then the strain passes, the self-collision and the
    /// normals.
    pub fn stages(&self, strain_passes: u32) -> Vec<Stage> {
        use Stage::*;
        let rk = |order: u8| {
            let mut v = vec![RkBegin];
            for stage in 0..order {
                v.extend([Eval, Rk { order, stage }]);
            }
            v.push(Collide);
            v
        };
        let mut v = match self.integrator {
            // In the (x, v) state both are one recurrence, v' = (1 − damping) v + f dt/m,
            // x' = x + v' dt (core::cpu::integrators).
            Integrator::Verlet | Integrator::SymplecticEuler => vec![Eval, Integrate, Collide],
            Integrator::Euler => vec![Eval, Euler, Collide],
            Integrator::Rk2 => rk(2),
            Integrator::Rk4 => rk(4),
            Integrator::Implicit => {
                let mut v = vec![Eval, CgBegin];
                v.extend((0..self.cg_iterations).map(|_| CgIteration));
                v.extend([ImplicitFinish, Collide]);
                v
            }
            Integrator::Xpbd => {
                let mut v = vec![Forces, Integrate];
                v.extend((0..self.xpbd_iterations).map(|_| XpbdIteration));
                v.push(Collide);
                v
            }
            Integrator::Vbd => {
                let mut v = vec![Forces, VbdBegin];
                for _ in 0..self.vbd_iterations {
                    v.push(VbdSweep);
                    if self.vbd_rho() > 0.0 {
                        v.push(VbdAccelerate);
                    }
                }
                v.extend([VbdFinish, Collide]);
                v
            }
        };
        if self.triangles {
            // Every integrator collides once, at its end: the separation goes before it
            // (the colliders then push out of what the separation pushed in), the
            // bounds before everything and the clamp after everything that moves.
            // XPBD takes the contacts as constraints of its iterations: the separation
            // after each (one iteration: the same place as the others').
            if self.integrator == Integrator::Xpbd {
                let mut k = 0;
                while k < v.len() {
                    if v[k] == XpbdIteration {
                        v.insert(k + 1, TriangleSeparate);
                    }
                    k += 1;
                }
            } else if let Some(k) = v.iter().rposition(|&s| s == Collide) {
                v.insert(k, TriangleSeparate);
            }
            v.insert(0, TriangleBounds);
        }
        v.extend((0..strain_passes).map(StrainPass));
        if self.self_collision {
            v.push(SelfCollision);
        }
        if self.triangles {
            v.push(TriangleClamp);
        }
        v.push(Normals);
        v
    }
}

/// One stage of a substep: what runs, not how (which kernels, fused with which, on
/// which lanes is each path's business).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// The force of the current (x, v): gravity, drag, wind and the springs.
    Eval,
    /// Gravity, drag and wind alone (XPBD and VBD: their solves take the springs).
    Forces,
    /// v' = (1 − damping) v + f dt/m, x' = x + v' dt (Verlet and symplectic Euler; XPBD's
    /// prediction).
    Integrate,
    /// Explicit Euler's update.
    Euler,
    /// Runge–Kutta's start: the substep's state kept, the sum cleared.
    RkBegin,
    /// Stage `stage` (from 0) of Runge–Kutta of order `order` (2 or 4), after the force
    /// at the stage's point.
    Rk {
        /// 2 or 4.
        order: u8,
        /// From 0.
        stage: u8,
    },
    /// Implicit Euler's system and the conjugate gradient's start (its first r·z).
    CgBegin,
    /// One conjugate-gradient iteration: A p, p·q, the step, r·z, the direction.
    CgIteration,
    /// Implicit Euler's update from the solution.
    ImplicitFinish,
    /// One XPBD iteration: a pass over each class of springs (a mesh: each colour's
    /// range); λ starts from zero at the substep's first.
    XpbdIteration,
    /// VBD's prediction.
    VbdBegin,
    /// One VBD sweep over the vertex colours.
    VbdSweep,
    /// VBD's Chebyshev step after the sweep before it.
    VbdAccelerate,
    /// VBD's velocities from the solved positions.
    VbdFinish,
    /// The colliders' response.
    Collide,
    /// Strain pass `k` (from 0): the over-stretched springs counted, then limited.
    StrainPass(u32),
    /// Particle–particle self-collision (the hash, then the response).
    SelfCollision,
    /// Contact between triangles: each vertex's bound on its motion in this substep, from
    /// the pairs of primitives near it at the substep's start.
    TriangleBounds,
    /// Contact between triangles: the pairs closer than the thickness pushed apart
    /// (before the colliders; under XPBD after each iteration, as its constraints).
    TriangleSeparate,
    /// Contact between triangles: every vertex's motion in the substep cut to its bound.
    TriangleClamp,
    /// Face and vertex normals (and the wind force they give).
    Normals,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_integrator_ends_with_the_colliders_then_the_strain_passes_and_the_normals() {
        for integrator in Integrator::ALL {
            let how = Integration {
                integrator,
                cg_iterations: 2,
                xpbd_iterations: 3,
                vbd_iterations: 2,
                vbd_rho_bits: 0.9f32.to_bits(),
                self_collision: true,
                ..Integration::VERLET
            };
            let s = how.stages(2);
            let tail =
                [Stage::Collide, Stage::StrainPass(0), Stage::StrainPass(1), Stage::SelfCollision, Stage::Normals];
            assert_eq!(s[s.len() - tail.len()..], tail, "{integrator:?}: {s:?}");
            let count = |st: Stage| s.iter().filter(|&&x| x == st).count();
            let iterations = match integrator {
                Integrator::Implicit => count(Stage::CgIteration),
                Integrator::Xpbd => count(Stage::XpbdIteration),
                Integrator::Vbd => count(Stage::VbdSweep) + count(Stage::VbdAccelerate),
                _ => 0,
            };
            let expected = match integrator {
                Integrator::Implicit => 2,
                Integrator::Xpbd => 3,
                Integrator::Vbd => 4,
                _ => 0,
            };
            assert_eq!(iterations, expected, "{integrator:?}");
        }
    }

    #[test]
    fn the_contact_between_triangles_separates_once_before_the_colliders_or_after_each_xpbd_iteration() {
        for integrator in Integrator::ALL {
            let how = Integration { integrator, xpbd_iterations: 3, triangles: true, ..Integration::VERLET };
            let s = how.stages(1);
            assert_eq!(s[0], Stage::TriangleBounds, "{integrator:?}");
            assert_eq!(s[s.len() - 2..], [Stage::TriangleClamp, Stage::Normals], "{integrator:?}: {s:?}");
            let after = |st: Stage| s.windows(2).filter(|w| w == &[st, Stage::TriangleSeparate]).count();
            let separations = s.iter().filter(|&&x| x == Stage::TriangleSeparate).count();
            if integrator == Integrator::Xpbd {
                assert_eq!((separations, after(Stage::XpbdIteration)), (3, 3), "{s:?}");
            } else {
                // Once, right before the colliders.
                let before = s.windows(2).filter(|w| w == &[Stage::TriangleSeparate, Stage::Collide]).count();
                assert_eq!((separations, before), (1, 1), "{integrator:?}: {s:?}");
            }
        }
    }
}
