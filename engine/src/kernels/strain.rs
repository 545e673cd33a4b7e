//! The strain limit (core::cpu::strain_limit): the counts of stretched springs and the
//! passes that divide by them.

use super::*;

/// Every particle's count of springs over their limit at the positions in `b`.
fn counts_of(a: &TwinArgs, b: &HostBuffers) -> Vec<f32> {
    let mut counts = vec![0.0; b.pos.len()];
    cpu::strain_count(a.exec, a.p, &a.topo.slots, &b.pos, &mut counts);
    counts
}

/// The counts as the kernel leaves them in aux0: `(count, 0, 0, 0)` per particle.
fn strain_count(a: &TwinArgs, b: &mut HostBuffers) {
    b.aux[0] = counts_of(a, b).into_iter().map(|c| [c, 0.0, 0.0, 0.0]).collect();
}

/// One pass dividing by `counts`, the velocities gaining the move.
fn limit_by(a: &TwinArgs, b: &mut HostBuffers, counts: &[f32]) {
    cpu::strain_limit(a.exec, a.p, &a.topo.slots, &a.topo.tethers, &b.pos, counts, &mut b.pos_out);
    cpu::strain_vel(a.exec, a.p, &b.pos, &b.pos_out, &mut b.vel);
}

fn strain_limit(a: &TwinArgs, b: &mut HostBuffers) {
    let counts: Vec<f32> = b.aux[0].iter().map(|c| c[0]).collect();
    limit_by(a, b, &counts);
}

/// A pass that counts for itself: the counts of its input, then the pass.
fn strain_limit_inline(a: &TwinArgs, b: &mut HostBuffers) {
    let counts = counts_of(a, b);
    limit_by(a, b, &counts);
}

/// The pass's output (`pos_out`) counted into the self-collision hash (the count's twin
/// on it).
fn then_hash_count(a: &TwinArgs, b: &mut HostBuffers) {
    std::mem::swap(&mut b.pos, &mut b.pos_out);
    (HASH_COUNT.twin)(a, b);
    std::mem::swap(&mut b.pos, &mut b.pos_out);
}

/// The strain limit's pass, then its output counted into the self-collision hash.
fn strain_limit_count(a: &TwinArgs, b: &mut HostBuffers) {
    strain_limit(a, b);
    then_hash_count(a, b);
}

/// The pass that counts for itself, then its output counted into the hash.
fn strain_limit_inline_count(a: &TwinArgs, b: &mut HostBuffers) {
    strain_limit_inline(a, b);
    then_hash_count(a, b);
}

/// Every particle's count of over-stretched strain-limited springs, into aux0 (dead
/// after the integrator's kernels): what the pass after it divides each spring by the
/// larger of its ends' counts of (the same at both ends: the pass keeps the momentum).
/// Timed as part of the strain limit.
pub static STRAIN_COUNT: KernelDef = KernelDef {
    check: GATHER,
    pure: &[STRAIN_COUNTS],
    variants: worlds(BLOCKED),
    label: timing::STRAIN_LIMIT,
    ..KernelDef::new(
        "strain_count",
        strain_count,
        Count::Blocks,
        &[Params, Pos, Slots, BendSlots, Adjacency, Interior, Table],
        &[STRAIN_COUNTS],
    )
};
/// One Provot pass plus the tethers, into the other buffer of the pair; the velocities
/// gain the move over dt.
pub static STRAIN_LIMIT: KernelDef = KernelDef {
    check: GATHER,
    pure: &[PosOut],
    variants: worlds(BLOCKED),
    // The counts it divides by, of the disturbed positions (as the recipe runs it).
    test_input: Some(strain_count),
    ..KernelDef::new(
        "strain_limit",
        strain_limit,
        Count::Blocks,
        &[Params, Pos, Vel, Slots, BendSlots, Adjacency, Interior, Table, Tethers, STRAIN_COUNTS],
        &[PosOut, Vel],
    )
};
/// [`STRAIN_LIMIT`] counting the springs over their limit itself (`strain_counts=inline`:
/// no [`STRAIN_COUNT`] dispatch before it): its own count from the window it loads, a
/// neighbour's only for a spring over its limit. The same counts, so the same twin.
pub static STRAIN_LIMIT_INLINE: KernelDef = KernelDef {
    check: GATHER,
    pure: &[PosOut],
    variants: worlds(BLOCKED),
    // Timed as the strain limit, as the count and the pass it replaces are.
    label: timing::STRAIN_LIMIT,
    ..KernelDef::new(
        "strain_limit_inline",
        strain_limit_inline,
        Count::Blocks,
        &[Params, Pos, Vel, Slots, BendSlots, Adjacency, Interior, Table, Tethers],
        &[PosOut, Vel],
    )
};
/// [`STRAIN_LIMIT_INLINE`] down strips of rows (`strain_counts=strip`): an invocation
/// carries a block's columns through [`STRIP_ROWS`](clothlab_core::layout::STRIP_ROWS)
/// rows, each spring's length computed once for the counts of both its ends and for the
/// pass. The same counts, so the same twin.
pub static STRAIN_LIMIT_STRIP: KernelDef = KernelDef {
    check: GATHER,
    pure: &[PosOut],
    variants: worlds(IMM_TEX),
    label: timing::STRAIN_LIMIT,
    ..KernelDef::new(
        "strain_limit_strip",
        strain_limit_inline,
        Count::Strips,
        &[Params, Pos, Vel, Slots, BendSlots, Adjacency, Interior, Table, Tethers],
        &[PosOut, Vel],
    )
};
/// The hash's counts of the positions the kernel wrote (`got.pos` after its swap): on a
/// GPU whose strain limit differs from the CPU's in a last bit, a point that close to a
/// cell's face may count in the next cell.
fn recount(p: &StepParams, got: &HostBuffers, want: &mut HostBuffers) {
    let [.., cells, totals, _] = &mut want.aux[..] else { unreachable!("the AUX buffers") };
    cells.iter_mut().chain(totals.iter_mut()).for_each(|c| *c = [0.0; 4]);
    cpu::hash_count(p, &got.pos, cells, totals);
}

/// The strain limit's last pass fused with self-collision's `hash_count` (the recipe's
/// choice when self-collision follows a strain limit): one dispatch fewer. Its counts are
/// checked against a recount of the positions it wrote (`recount`; the positions
/// themselves against the twin's, within the bound); a wrong count is off by a whole
/// particle, far past the positions' bound, so the bound leaves the counts exact.
pub static STRAIN_LIMIT_COUNT: KernelDef = KernelDef {
    check: GATHER,
    pure: &[PosOut],
    accumulates: &[HASH_CELLS, HASH_TOTALS],
    variants: worlds(BLOCKED),
    test_input: Some(strain_count),
    label: timing::STRAIN_LIMIT_COUNT,
    from_output: Some(recount),
    ..KernelDef::new(
        "strain_limit_count",
        strain_limit_count,
        Count::Blocks,
        &[
            Params,
            Pos,
            Vel,
            Slots,
            BendSlots,
            Adjacency,
            Interior,
            Table,
            Tethers,
            STRAIN_COUNTS,
            HASH_CELLS,
            HASH_TOTALS,
        ],
        &[PosOut, Vel, HASH_CELLS, HASH_TOTALS],
    )
};

/// [`STRAIN_LIMIT_COUNT`] counting the springs over their limit itself
/// (`strain_counts=inline`, as [`STRAIN_LIMIT_INLINE`]).
pub static STRAIN_LIMIT_INLINE_COUNT: KernelDef = KernelDef {
    check: GATHER,
    pure: &[PosOut],
    accumulates: &[HASH_CELLS, HASH_TOTALS],
    variants: worlds(BLOCKED),
    label: timing::STRAIN_LIMIT_COUNT,
    from_output: Some(recount),
    ..KernelDef::new(
        "strain_limit_inline_count",
        strain_limit_inline_count,
        Count::Blocks,
        &[Params, Pos, Vel, Slots, BendSlots, Adjacency, Interior, Table, Tethers, HASH_CELLS, HASH_TOTALS],
        &[PosOut, Vel, HASH_CELLS, HASH_TOTALS],
    )
};

/// [`STRAIN_LIMIT_INLINE_COUNT`] down strips of rows (`strain_counts=strip`, as
/// [`STRAIN_LIMIT_STRIP`]).
pub static STRAIN_LIMIT_STRIP_COUNT: KernelDef = KernelDef {
    check: GATHER,
    pure: &[PosOut],
    accumulates: &[HASH_CELLS, HASH_TOTALS],
    variants: worlds(IMM_TEX),
    label: timing::STRAIN_LIMIT_COUNT,
    from_output: Some(recount),
    ..KernelDef::new(
        "strain_limit_strip_count",
        strain_limit_inline_count,
        Count::Strips,
        &[Params, Pos, Vel, Slots, BendSlots, Adjacency, Interior, Table, Tethers, HASH_CELLS, HASH_TOTALS],
        &[PosOut, Vel, HASH_CELLS, HASH_TOTALS],
    )
};

/// This family's kernels, in the registry's order ([`super::ALL`]).
pub(super) const ROWS: &[&KernelDef] = &[&STRAIN_COUNT, &STRAIN_LIMIT, &STRAIN_LIMIT_INLINE, &STRAIN_LIMIT_STRIP];
