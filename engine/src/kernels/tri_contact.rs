//! The contact between triangles (core::cpu::tri_contact, whose functions are these
//! kernels' twins; docs/contact.md): at the substep's start the reach, the grid of the
//! primitives' boxes, each owner's pairs, the bounds and the velocity pass; after the
//! integrator the separation's passes; at the end the clamp.

use clothlab_cpu::tri_contact::{self as tc, Pass, TriBufs, TriLayout};

use super::*;

/// The state and the contact's buffers of `b`, sized for `a`'s cloth.
fn split<'b>(a: &TwinArgs, b: &'b mut HostBuffers) -> (&'b mut Vec<V4>, &'b mut Vec<V4>, TriBufs<'b>) {
    let l = TriLayout::of(a.topo);
    b.tri_sized(l);
    let HostBuffers { pos, vel, tri_floats, tri_ints, tri_pairs, .. } = b;
    let ints: &mut [u32] = bytemuck::cast_slice_mut(tri_ints.as_mut_slice());
    let pairs: &mut [u32] = bytemuck::cast_slice_mut(tri_pairs.as_mut_slice());
    let min_len = if a.exec == cpu::Exec::Parallel { 1 } else { usize::MAX };
    let t =
        TriBufs { l, floats: tri_floats, ints: &mut ints[..l.words()], pairs: &mut pairs[..l.pair_words()], min_len };
    (pos, vel, t)
}

fn tri_speed(a: &TwinArgs, b: &mut HostBuffers) {
    let (pos, vel, mut t) = split(a, b);
    tc::tri_speed(pos, vel, &mut t);
}

fn tri_start(a: &TwinArgs, b: &mut HostBuffers) {
    let (pos, _, mut t) = split(a, b);
    tc::tri_start(a.p, pos, &mut t);
}

fn tri_grid_count(a: &TwinArgs, b: &mut HostBuffers) {
    let (pos, _, mut t) = split(a, b);
    tc::tri_grid_count(tc::Prims::of(a.topo), pos, &mut t);
}

fn tri_grid_scan(a: &TwinArgs, b: &mut HostBuffers) {
    tc::tri_grid_scan(&mut split(a, b).2);
}

fn tri_grid_scatter(a: &TwinArgs, b: &mut HostBuffers) {
    let (pos, _, mut t) = split(a, b);
    tc::tri_grid_scatter(tc::Prims::of(a.topo), pos, &mut t);
}

fn tri_grid_sort(a: &TwinArgs, b: &mut HostBuffers) {
    tc::tri_grid_sort(&mut split(a, b).2);
}

fn tri_pairs(a: &TwinArgs, b: &mut HostBuffers) {
    let (pos, _, mut t) = split(a, b);
    tc::tri_pairs(tc::Prims::of(a.topo), pos, &mut t);
}

fn count(a: &TwinArgs, b: &mut HostBuffers, pass: Pass) {
    let (pos, vel, mut t) = split(a, b);
    tc::tri_count(a.p, tc::Prims::of(a.topo), pos, vel, &mut t, pass);
}

fn share(a: &TwinArgs, b: &mut HostBuffers, pass: Pass) {
    let (pos, vel, mut t) = split(a, b);
    tc::tri_share(a.p, tc::Prims::of(a.topo), pos, vel, &mut t, pass);
}

fn apply(a: &TwinArgs, b: &mut HostBuffers, pass: Pass) {
    let (pos, vel, mut t) = split(a, b);
    tc::tri_apply(a.p, pos, vel, &mut t, pass);
}

fn tri_impulse_count(a: &TwinArgs, b: &mut HostBuffers) {
    count(a, b, Pass::Velocity)
}

fn tri_impulse_share(a: &TwinArgs, b: &mut HostBuffers) {
    share(a, b, Pass::Velocity)
}

fn tri_impulse_apply(a: &TwinArgs, b: &mut HostBuffers) {
    apply(a, b, Pass::Velocity)
}

fn tri_separate_count(a: &TwinArgs, b: &mut HostBuffers) {
    count(a, b, Pass::Separation)
}

fn tri_separate_share(a: &TwinArgs, b: &mut HostBuffers) {
    share(a, b, Pass::Separation)
}

fn tri_separate_apply(a: &TwinArgs, b: &mut HostBuffers) {
    apply(a, b, Pass::Separation)
}

fn tri_clamp_sum(a: &TwinArgs, b: &mut HostBuffers) {
    let (pos, _, mut t) = split(a, b);
    tc::tri_clamp_sum(pos, &mut t);
}

fn tri_clamp_check(a: &TwinArgs, b: &mut HostBuffers) {
    let (pos, _, mut t) = split(a, b);
    tc::tri_clamp_check(pos, &mut t);
}

fn tri_clamp(a: &TwinArgs, b: &mut HostBuffers) {
    let (pos, vel, mut t) = split(a, b);
    tc::tri_clamp(a.p, pos, vel, &mut t);
}

fn tri_vbd(a: &TwinArgs, b: &mut HostBuffers) {
    let (pos, _, mut t) = split(a, b);
    tc::tri_vbd(a.p, tc::Prims::of(a.topo), &a.topo.colours.of, pos, a.range.0, &mut t);
}

/// One colour of VBD's sweep with the contact's terms (`core::cpu::vbd::vbd_colour` with
/// `TriVbd`): particles `first .. first + count` of the colouring's list.
fn vbd_colour_tri(a: &TwinArgs, b: &mut HostBuffers) {
    let l = TriLayout::of(a.topo);
    b.tri_sized(l);
    let list = super::vbd::colour_list(a);
    let HostBuffers { pos, aux, tri_ints, .. } = b;
    let ints: &mut [u32] = bytemuck::cast_slice_mut(tri_ints.as_mut_slice());
    let tri = cpu::vbd::TriVbd { sums: &mut ints[l.vbd()..l.words()], pos };
    cpu::vbd::vbd_colour(a.exec, a.p, &a.topo.slots, a.colliders, list, aux, Some(tri));
}

fn vbd_positions(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::vbd::vbd_positions(a.exec, &mut b.pos, &b.aux);
}

/// The kernels in the recipe's order (the separation's three once), for the kernel
/// tests' inputs: each kernel's input is the twins before it run from the disturbed
/// state, the integers cleared first as the recipe clears them.
const ORDER: [Twin; 16] = [
    tri_speed,
    tri_start,
    tri_grid_count,
    tri_grid_scan,
    tri_grid_scatter,
    tri_grid_sort,
    tri_pairs,
    tri_impulse_count,
    tri_impulse_share,
    tri_impulse_apply,
    tri_separate_count,
    tri_separate_share,
    tri_separate_apply,
    tri_clamp_sum,
    tri_clamp_check,
    tri_clamp,
];

fn upto(a: &TwinArgs, b: &mut HostBuffers, n: usize) {
    let (_, _, t) = split(a, b);
    t.ints.fill(0);
    for twin in &ORDER[..n] {
        twin(a, b);
    }
}

macro_rules! inputs {
    ($($name:ident = $n:expr),*) => {
        $(fn $name(a: &TwinArgs, b: &mut HostBuffers) { upto(a, b, $n) })*
    };
}
inputs!(
    after_speed = 1,
    after_start = 2,
    after_count = 3,
    after_scan = 4,
    after_scatter = 5,
    after_sort = 6,
    after_pairs = 7,
    after_impulse_count = 8,
    after_impulse_share = 9,
    after_impulses = 10,
    after_separate_count = 11,
    after_separate_share = 12,
    after_separation = 13,
    after_clamp_sum = 14,
    after_clamp_check = 15
);

/// VBD's sweep's input: the start stage's pairs (the velocity pass done), VBD's prediction
/// from the disturbed state and the positions at its iterate.
fn after_vbd_begin(a: &TwinArgs, b: &mut HostBuffers) {
    upto(a, b, 10);
    cpu::vbd::vbd_begin(a.exec, a.p, &b.force, &b.pos, &b.vel, &mut b.aux);
    vbd_positions(a, b);
}

/// The first kernel's input: the integers cleared (the recipe clears them before it).
fn cleared(a: &TwinArgs, b: &mut HostBuffers) {
    upto(a, b, 0)
}

/// The contact's integers and pairs are compared exactly (validate.rs); the positions
/// and velocities within this.
const TRI: Check = Check::Bound {
    relative: 2e-5,
    reason: "closest points, a division and square roots per pair, sums in fixed point \
             (lavapipe and llvmpipe: exact; the integers and pairs are compared exactly)",
};

const fn row(
    name: &'static str,
    twin: Twin,
    count: Count,
    reads: &'static [Buf],
    writes: &'static [Buf],
    label: &'static str,
    input: Twin,
) -> KernelDef {
    KernelDef {
        check: TRI,
        label,
        test_input: Some(input),
        variants: worlds(Variants { immediates: true, ..PLAIN }),
        ..KernelDef::new(name, twin, count, reads, writes)
    }
}

const B: &str = timing::TRI_BOUNDS;
const C: &str = timing::TRI_CONTACT;

/// The fastest free vertex's speed (the integers cleared before).
pub static TRI_SPEED: KernelDef = KernelDef {
    accumulates: &[TriInts],
    ..row("tri_speed", tri_speed, Count::Particles, &[Params, Pos, Vel, TriEdges, TriInts], &[TriInts], B, cleared)
};
/// Each particle's start and bound at the reach's fraction; the reach and the cell.
pub static TRI_START: KernelDef = row(
    "tri_start",
    tri_start,
    Count::Particles,
    &[Params, Pos, TriEdges, TriInts],
    &[TriFloats, TriInts],
    B,
    after_speed,
);
/// The primitives' bucket counts and largest extents.
pub static TRI_GRID_COUNT: KernelDef = row(
    "tri_grid_count",
    tri_grid_count,
    Count::Primitives,
    &[Params, Pos, Triangles, TriEdges, TriInts],
    &[TriInts],
    B,
    after_start,
);
/// The buckets' starts (one workgroup).
pub static TRI_GRID_SCAN: KernelDef =
    row("tri_grid_scan", tri_grid_scan, Count::Workgroup, &[Params, TriEdges, TriInts], &[TriInts], B, after_count);
/// The primitives into their buckets.
pub static TRI_GRID_SCATTER: KernelDef = row(
    "tri_grid_scatter",
    tri_grid_scatter,
    Count::Primitives,
    &[Params, Pos, Triangles, TriEdges, TriInts],
    &[TriInts],
    B,
    after_scan,
);
/// Each bucket's entries in order.
pub static TRI_GRID_SORT: KernelDef =
    row("tri_grid_sort", tri_grid_sort, Count::TriBuckets, &[Params, TriEdges, TriInts], &[TriInts], B, after_scatter);
/// Each owner's pairs within the reach; the bounds.
pub static TRI_PAIRS: KernelDef = row(
    "tri_pairs",
    tri_pairs,
    Count::TriOwners,
    &[Params, Pos, Triangles, TriEdges, TriFloats, TriInts, TriPairs],
    &[TriFloats, TriInts, TriPairs],
    B,
    after_sort,
);
const PASS_READS: &[Buf] = &[Params, Pos, Vel, Triangles, TriEdges, TriInts, TriPairs];
/// The velocity pass: each vertex's count of impulses.
pub static TRI_IMPULSE_COUNT: KernelDef =
    row("tri_impulse_count", tri_impulse_count, Count::TriOwners, PASS_READS, &[TriInts], B, after_pairs);
/// The velocity pass: the impulses into the sums.
pub static TRI_IMPULSE_SHARE: KernelDef =
    row("tri_impulse_share", tri_impulse_share, Count::TriOwners, PASS_READS, &[TriInts], B, after_impulse_count);
/// The velocity pass: the sums into the velocities.
pub static TRI_IMPULSE_APPLY: KernelDef = row(
    "tri_impulse_apply",
    tri_impulse_apply,
    Count::Particles,
    &[Params, Pos, Vel, TriEdges, TriInts],
    &[Vel, TriInts],
    B,
    after_impulse_share,
);
/// A separation pass: each vertex's count of pushes.
pub static TRI_SEPARATE_COUNT: KernelDef =
    row("tri_separate_count", tri_separate_count, Count::TriOwners, PASS_READS, &[TriInts], C, after_impulses);
/// A separation pass: the pushes into the sums.
pub static TRI_SEPARATE_SHARE: KernelDef =
    row("tri_separate_share", tri_separate_share, Count::TriOwners, PASS_READS, &[TriInts], C, after_separate_count);
/// A separation pass: the sums into the positions and velocities.
pub static TRI_SEPARATE_APPLY: KernelDef = row(
    "tri_separate_apply",
    tri_separate_apply,
    Count::Particles,
    &[Params, Pos, Vel, TriEdges, TriInts],
    &[Pos, Vel, TriInts],
    C,
    after_separate_share,
);
/// The clamp: the free vertices' displacement sums.
pub static TRI_CLAMP_SUM: KernelDef = row(
    "tri_clamp_sum",
    tri_clamp_sum,
    Count::Particles,
    &[Params, Pos, TriEdges, TriFloats, TriInts],
    &[TriInts],
    C,
    after_separation,
);
/// The clamp: whether some vertex is over its bound from the mean.
pub static TRI_CLAMP_CHECK: KernelDef = row(
    "tri_clamp_check",
    tri_clamp_check,
    Count::Particles,
    &[Params, Pos, TriEdges, TriFloats, TriInts],
    &[TriInts],
    C,
    after_clamp_sum,
);
/// The clamp: every vertex's motion cut to its bound where some is over.
pub static TRI_CLAMP: KernelDef = row(
    "tri_clamp",
    tri_clamp,
    Count::Particles,
    &[Params, Pos, Vel, TriEdges, TriFloats, TriInts],
    &[Pos, Vel, TriInts],
    C,
    after_clamp_check,
);

/// VBD with the contact: the positions at the iterate x⁰ + D (after the prediction and
/// each Chebyshev step).
pub static VBD_POSITIONS: KernelDef = KernelDef {
    label: timing::VBD,
    ..row("vbd_positions", vbd_positions, Count::Particles, &[Params, Aux1, Aux2], &[Pos], timing::VBD, after_vbd_begin)
};
/// VBD with the contact: one colour's terms of every owner's kept pairs at the iterate,
/// into the colour's particles' sums (the colour's index the range's `first`).
pub static TRI_VBD: KernelDef = KernelDef {
    immediates: Immediates::Range,
    dispatches: Dispatches::ContactColours,
    variants: worlds(PLAIN),
    ..row(
        "tri_vbd",
        tri_vbd,
        Count::Range,
        &[Params, Pos, Triangles, TriEdges, TriInts, TriPairs, Colours],
        &[TriInts],
        timing::VBD,
        after_vbd_begin,
    )
};
/// VBD with the contact: one colour's Newton steps (`vbd_colour`'s) with the colour's
/// contact terms in each block (taken and cleared), its positions kept at the iterate;
/// each colour after its `tri_vbd`.
pub static VBD_COLOUR_TRI: KernelDef = KernelDef {
    check: Check::Bound {
        relative: 2e-5,
        reason: "vbd_colour's block and solve (a division and square roots a spring, exact on llvmpipe), \
                 with the colour's integer terms; checked over one colour (validate.rs says why)",
    },
    variants: worlds(Variants { table_image: true, colliders_uniform: true, sdf_image: true, ..PLAIN }),
    immediates: Immediates::Range,
    dispatches: Dispatches::ColoursWithContact,
    ..row(
        "vbd_colour_tri",
        vbd_colour_tri,
        Count::Range,
        &[Params, Colours, Slots, BendSlots, Adjacency, Table, Spheres, Boxes, Shapes, Aux0, Aux1, Aux2, TriInts, Pos],
        &[Aux2, Pos, TriInts],
        timing::VBD,
        after_vbd_begin,
    )
};

/// The stage at the substep's start, in order.
pub static TRI_BEGIN: [&KernelDef; 10] = [
    &TRI_SPEED,
    &TRI_START,
    &TRI_GRID_COUNT,
    &TRI_GRID_SCAN,
    &TRI_GRID_SCATTER,
    &TRI_GRID_SORT,
    &TRI_PAIRS,
    &TRI_IMPULSE_COUNT,
    &TRI_IMPULSE_SHARE,
    &TRI_IMPULSE_APPLY,
];
/// One pass of the separation.
pub static TRI_SEPARATE: [&KernelDef; 3] = [&TRI_SEPARATE_COUNT, &TRI_SEPARATE_SHARE, &TRI_SEPARATE_APPLY];
/// The clamp.
pub static TRI_CLAMP_STAGE: [&KernelDef; 3] = [&TRI_CLAMP_SUM, &TRI_CLAMP_CHECK, &TRI_CLAMP];

/// This family's kernels, in the registry's order ([`super::ALL`]).
pub(super) const ROWS: &[&KernelDef] = &[
    &TRI_SPEED,
    &TRI_START,
    &TRI_GRID_COUNT,
    &TRI_GRID_SCAN,
    &TRI_GRID_SCATTER,
    &TRI_GRID_SORT,
    &TRI_PAIRS,
    &TRI_IMPULSE_COUNT,
    &TRI_IMPULSE_SHARE,
    &TRI_IMPULSE_APPLY,
    &TRI_SEPARATE_COUNT,
    &TRI_SEPARATE_SHARE,
    &TRI_SEPARATE_APPLY,
    &TRI_CLAMP_SUM,
    &TRI_CLAMP_CHECK,
    &TRI_CLAMP,
    &VBD_POSITIONS,
    &TRI_VBD,
    &VBD_COLOUR_TRI,
];

/// Every kernel of the contact, in the recipe's order.
pub static TRI_CONTACT_KERNELS: &[&KernelDef] = ROWS;
