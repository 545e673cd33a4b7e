//! The statistics of a substep (core::cpu::stats): the largest strain and the kinetic
//! energy, by subgroups or by atomics, and their reduction.

use super::*;

fn stats(a: &TwinArgs, b: &mut HostBuffers) {
    let k = a.substep as usize;
    if b.stats.len() <= k {
        b.stats.resize(k + 1, SubstepStats { max_strain: 0.0, kinetic_energy: 0.0 });
    }
    b.stats[k] = cpu::substep_stats(a.p, &a.topo.slots, &b.pos, &b.vel);
}

/// Statistics by subgroup and workgroup reductions: one partial per workgroup.
pub static STATS: KernelDef = KernelDef {
    check: STATS_TEST,
    label: timing::STATS,
    variants: Variants { table_image: true, ..PLAIN },
    immediates: Immediates::Substep,
    ..KernelDef::new(
        "stats",
        stats,
        Count::Particles,
        &[Params, Pos, Vel, Slots, BendSlots, Adjacency, Table],
        &[Partials],
    )
};
/// Statistics by atomics from every invocation.
pub static STATS_ATOMIC: KernelDef = KernelDef {
    check: STATS_TEST,
    label: timing::STATS,
    variants: Variants { table_image: true, float_atomics: true, ..PLAIN },
    immediates: Immediates::Substep,
    ..KernelDef::new(
        "stats_atomic",
        stats,
        Count::Particles,
        &[Params, Pos, Vel, Slots, BendSlots, Adjacency, Table, StatsMax, StatsEnergy],
        &[StatsMax, StatsEnergy],
    )
};
/// The statistics' final fold of the partials.
pub static STATS_REDUCE: KernelDef = KernelDef {
    check: STATS_TEST,
    label: timing::STATS,
    variants: PLAIN,
    immediates: Immediates::Substep,
    ..KernelDef::new(
        "stats_reduce",
        nothing,
        Count::Workgroup,
        &[Params, Partials, StatsMax, StatsEnergy],
        &[StatsMax, StatsEnergy],
    )
};

/// This family's kernels, in the registry's order ([`super::ALL`]).
pub(super) const ROWS: &[&KernelDef] = &[&STATS, &STATS_ATOMIC, &STATS_REDUCE];
