//! Explicit Euler and the Runge–Kutta integrators (core::cpu::integrators).

use super::*;

fn euler(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::euler(a.exec, a.p, &b.force, &mut b.pos, &mut b.vel);
}

fn rk_begin(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::rk_begin(a.exec, a.p, &b.force, &b.pos, &mut b.vel, &mut b.aux);
}

fn rk_stage(a: &TwinArgs, b: &mut HostBuffers, st: &cpu::RkStage) {
    cpu::rk_stage(a.exec, a.p, st, &mut b.force, &mut b.pos, &mut b.vel, &mut b.aux);
}

fn rk2_1(a: &TwinArgs, b: &mut HostBuffers) {
    rk_stage(a, b, &cpu::RK2[0]);
}

fn rk2_2(a: &TwinArgs, b: &mut HostBuffers) {
    rk_stage(a, b, &cpu::RK2[1]);
}

fn rk4_1(a: &TwinArgs, b: &mut HostBuffers) {
    rk_stage(a, b, &cpu::RK4[0]);
}

fn rk4_2(a: &TwinArgs, b: &mut HostBuffers) {
    rk_stage(a, b, &cpu::RK4[1]);
}

fn rk4_3(a: &TwinArgs, b: &mut HostBuffers) {
    rk_stage(a, b, &cpu::RK4[2]);
}

fn rk4_4(a: &TwinArgs, b: &mut HostBuffers) {
    rk_stage(a, b, &cpu::RK4[3]);
}

const RK_READS: &[Buf] = &[Params, Pos, Vel, Force, RK_X0, RK_V0, RK_SUM_V, RK_SUM_A, RK_WIND];
/// Explicit Euler: `x' = x + u`, `u' = u + f dt²/m`.
pub static EULER: KernelDef = KernelDef {
    label: timing::INTEGRATE,
    variants: worlds(Variants { immediates: true, ..PLAIN }),
    ..KernelDef::new("euler", euler, Count::Particles, STATE, &[Pos, Vel])
};
/// Saves x₀, the damped v₀ and the wind for a Runge–Kutta substep.
pub static RK_BEGIN: KernelDef = KernelDef {
    label: timing::INTEGRATE,
    pure: &[RK_X0, RK_V0, RK_WIND],
    variants: worlds(Variants { immediates: true, ..PLAIN }),
    ..KernelDef::new("rk_begin", rk_begin, Count::Particles, STATE, &[Vel, RK_X0, RK_V0, RK_WIND])
};
/// A stage kernel (every stage's shader has the force write; the last one never runs it).
const fn rk(name: &'static str, twin: Twin) -> KernelDef {
    KernelDef {
        label: timing::INTEGRATE,
        variants: worlds(Variants { immediates: true, ..PLAIN }),
        ..KernelDef::new(name, twin, Count::Particles, RK_READS, &[Pos, Vel, Force, RK_SUM_V, RK_SUM_A])
    }
}
/// RK2's first stage (to the midpoint).
pub static RK2_1: KernelDef = rk("rk2_1", rk2_1);
/// RK2's second stage (the end of the substep).
pub static RK2_2: KernelDef = rk("rk2_2", rk2_2);
/// RK4's first stage.
pub static RK4_1: KernelDef = rk("rk4_1", rk4_1);
/// RK4's second stage.
pub static RK4_2: KernelDef = rk("rk4_2", rk4_2);
/// RK4's third stage.
pub static RK4_3: KernelDef = rk("rk4_3", rk4_3);
/// RK4's fourth stage (the end of the substep).
pub static RK4_4: KernelDef = rk("rk4_4", rk4_4);

/// This family's kernels, in the registry's order ([`super::ALL`]).
pub(super) const ROWS: &[&KernelDef] = &[&EULER, &RK_BEGIN, &RK2_1, &RK2_2, &RK4_1, &RK4_2, &RK4_3, &RK4_4];
