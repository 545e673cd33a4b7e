//! Implicit Euler by conjugate gradients (core::cpu::integrators): the matrix-free
//! product, the reductions of the dot products and the steps.

use super::*;

/// Leaves the per-workgroup sums of `terms` in `aux[4]` (the GPU kernels' partials).
fn store_partials(b: &mut HostBuffers, terms: &[f32]) {
    for (g, s) in cpu::partial_sums(terms).into_iter().enumerate() {
        b.aux[4][g] = [s, 0.0, 0.0, 0.0];
    }
}

/// The partials' fold (what the reduction kernels compute in one workgroup).
fn partials_total(a: &TwinArgs, b: &HostBuffers) -> f32 {
    let groups = (a.topo.num_particles() as u32).div_ceil(WORKGROUP) as usize;
    cpu::fold(&b.aux[4][..groups].iter().map(|v| v[0]).collect::<Vec<_>>())
}

fn cg_begin(a: &TwinArgs, b: &mut HostBuffers) {
    let terms = cpu::cg_begin(a.exec, a.p, &a.topo.slots, &b.force, &b.pos, &b.vel, &mut b.aux);
    store_partials(b, &terms);
}

fn cg_matvec(a: &TwinArgs, b: &mut HostBuffers) {
    let terms = cpu::cg_matvec(a.exec, a.p, &a.topo.slots, &b.pos, &mut b.aux);
    store_partials(b, &terms);
}

fn cg_step(a: &TwinArgs, b: &mut HostBuffers) {
    let terms = cpu::cg_step(a.exec, &b.scalars[0], &mut b.aux);
    store_partials(b, &terms);
}

fn cg_reduce_pq(a: &TwinArgs, b: &mut HostBuffers) {
    let total = partials_total(a, b);
    cpu::cg_alpha(&mut b.scalars[0], total);
}

fn cg_reduce_rz(a: &TwinArgs, b: &mut HostBuffers) {
    let total = partials_total(a, b);
    cpu::cg_beta(&mut b.scalars[0], total);
}

fn cg_direction(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::cg_direction(a.exec, &b.scalars[0], &mut b.aux);
}

fn implicit_finish(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::implicit_finish(a.exec, a.p, &mut b.pos, &mut b.vel, &b.aux);
}

/// Conjugate gradients: dot products summed per workgroup (in a tree on the GPU, in order
/// on the CPU) and over 16 iterations; the rollout's bound covers the rest.
const CG: Check = Check::Bound {
    relative: 1e-4,
    reason: "dot products summed in another order (tree per workgroup vs in order), divided into α and β",
};
const CG_PARTIALS: &[Buf] = &[Params, CG_SUMS, Scalars];
/// Implicit: r = dt f − dt² K v, p = z, Δv = 0, and the partials of r·z.
pub static CG_BEGIN: KernelDef = KernelDef {
    check: GATHER,
    label: timing::CG,
    variants: worlds(IMM_TEX),
    ..KernelDef::new(
        "cg_begin",
        cg_begin,
        Count::Particles,
        &[Params, Pos, Vel, Force, Slots, BendSlots, Adjacency, Table, CG_P],
        &[CG_DV, CG_R, CG_P, CG_SUMS],
    )
};
/// Implicit: q = A p and the partials of p·q.
pub static CG_MATVEC: KernelDef = KernelDef {
    check: GATHER,
    label: timing::CG,
    variants: worlds(IMM_TEX),
    ..KernelDef::new(
        "cg_matvec",
        cg_matvec,
        Count::Particles,
        &[Params, Pos, Vel, Slots, BendSlots, Adjacency, Table, CG_P],
        &[CG_Q, CG_SUMS],
    )
};
/// Implicit: p·q folded, α = r·z / p·q.
pub static CG_REDUCE_PQ: KernelDef = KernelDef {
    variants: worlds(Variants { immediates: true, ..PLAIN }),
    check: CG,
    label: timing::CG,
    ..KernelDef::new("cg_reduce_pq", cg_reduce_pq, Count::Workgroup, CG_PARTIALS, &[Scalars])
};
/// Implicit: Δv += α p, r −= α q, and the partials of r·z.
pub static CG_STEP: KernelDef = KernelDef {
    variants: worlds(Variants { immediates: true, ..PLAIN }),
    check: CG,
    label: timing::CG,
    ..KernelDef::new(
        "cg_step",
        cg_step,
        Count::Particles,
        &[Params, CG_DV, CG_R, CG_P, CG_Q, Scalars],
        &[CG_DV, CG_R, CG_SUMS],
    )
};
/// Implicit: r·z folded, β = new / old.
pub static CG_REDUCE_RZ: KernelDef = KernelDef {
    variants: worlds(Variants { immediates: true, ..PLAIN }),
    check: CG,
    label: timing::CG,
    ..KernelDef::new("cg_reduce_rz", cg_reduce_rz, Count::Workgroup, CG_PARTIALS, &[Scalars])
};
/// Implicit: p = z + β p.
pub static CG_DIRECTION: KernelDef = KernelDef {
    variants: worlds(Variants { immediates: true, ..PLAIN }),
    check: CG,
    label: timing::CG,
    ..KernelDef::new("cg_direction", cg_direction, Count::Particles, &[Params, CG_R, CG_P, Scalars], &[CG_P])
};
/// Implicit: v₁ = (1 − damping) v₀ + Δv, x₁ = x₀ + v₁ dt, with pins, grab and floor.
pub static IMPLICIT_FINISH: KernelDef = KernelDef {
    variants: worlds(Variants { immediates: true, ..PLAIN }),
    label: timing::INTEGRATE,
    ..KernelDef::new("implicit_finish", implicit_finish, Count::Particles, &[Params, Pos, Vel, CG_DV], &[Pos, Vel])
};

/// This family's kernels, in the registry's order ([`super::ALL`]).
pub(super) const ROWS: &[&KernelDef] =
    &[&CG_BEGIN, &CG_MATVEC, &CG_REDUCE_PQ, &CG_STEP, &CG_REDUCE_RZ, &CG_DIRECTION, &IMPLICIT_FINISH];
