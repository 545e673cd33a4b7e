//! Self-collision (core::cpu::self_collide): the spatial hash (count, scan, scatter) and
//! the response, on a grid and on a mesh, with and without friction; the strain limit's
//! last pass with the hash's count fused in.

use super::*;

fn hash_buffers(b: &mut HostBuffers) -> cpu::HashBuffers<'_> {
    cpu::hash_buffers(&mut b.aux)
}

fn hash_count(a: &TwinArgs, b: &mut HostBuffers) {
    let h = cpu::hash_buffers(&mut b.aux);
    cpu::hash_count(a.p, &b.pos, h.cells, h.totals);
}

fn hash_scan_blocks(_: &TwinArgs, b: &mut HostBuffers) {
    let h = hash_buffers(b);
    cpu::hash_scan_blocks(h.cells, h.totals);
}

fn hash_scan_top(_: &TwinArgs, b: &mut HostBuffers) {
    cpu::hash_scan_top(hash_buffers(b).totals);
}

fn hash_scatter(a: &TwinArgs, b: &mut HostBuffers) {
    let h = cpu::hash_buffers(&mut b.aux);
    cpu::hash_scatter(a.p, &b.pos, &b.vel, h.cells, h.slots, h.vel_copy);
}

/// `self_collide` and `self_collide_mesh`: the response without friction between
/// particles, whatever the parameters (the recipe takes the `_friction` kernels where they
/// have Coulomb's coefficients).
fn self_collide(a: &TwinArgs, b: &mut HostBuffers) {
    self_collide_with(a, &a.p.without_coulomb(), b);
}

/// `self_collide_friction` and `self_collide_mesh_friction`: the response with Coulomb
/// friction at its contacts where the parameters have the coefficients.
fn self_collide_friction(a: &TwinArgs, b: &mut HostBuffers) {
    self_collide_with(a, a.p, b);
}

fn self_collide_with(a: &TwinArgs, p: &clothlab_core::StepParams, b: &mut HostBuffers) {
    let [vel_copy, _, cells, _, slots] = &b.aux[..] else { unreachable!("HostBuffers has the AUX buffers") };
    cpu::self_collide(a.exec, p, &b.pos, &mut b.vel, cells, slots, vel_copy, Some(&a.topo.slots), &mut b.pos_out);
}

/// Kernel-test inputs: the hash built by the twins up to the kernel under test (the
/// counts cleared first, as the recipe does).
fn hash_input(upto: usize) -> impl Fn(&TwinArgs, &mut HostBuffers) {
    move |a, b| {
        let h = hash_buffers(b);
        h.cells.iter_mut().chain(h.totals.iter_mut()).for_each(|c| *c = [0.0; 4]);
        let steps: [Twin; 4] = [hash_count, hash_scan_top, hash_scan_blocks, hash_scatter];
        for step in &steps[..upto] {
            step(a, b);
        }
    }
}

fn after_count(a: &TwinArgs, b: &mut HostBuffers) {
    hash_input(1)(a, b)
}

fn after_top(a: &TwinArgs, b: &mut HostBuffers) {
    hash_input(2)(a, b)
}

fn after_scan(a: &TwinArgs, b: &mut HostBuffers) {
    hash_input(3)(a, b)
}

/// Every `every`-th particle `i` put within 0.3–0.8 thicknesses `t` of particle
/// `i + apart` (mod the count), velocity kept: contacts from a start the cloth did not
/// reach (the response's checks, and the worlds' contact tests).
pub fn crowd(pos: &mut [[f32; 4]], t: f32, apart: usize, every: usize) {
    let np = pos.len();
    for i in (0..np).step_by(every) {
        let q = (i + apart) % np;
        let off = t * (0.3 + 0.5 * ((i / every) % 5) as f32 / 4.0);
        let dir: [f32; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.6, 0.8, 0.0]][(i / every) % 4];
        for (c, d) in dir.iter().enumerate() {
            pos[i][c] = pos[q][c] + off * d;
        }
    }
}

/// The response's input: every 7th particle put within 0.3–0.8 thicknesses of one far
/// away in the grid (half the cloth on), velocity kept, so that contacts are many; then
/// the hash built.
fn built_hash(a: &TwinArgs, b: &mut HostBuffers) {
    let np = b.pos.len();
    crowd(&mut b.pos, a.p.self_thickness, np / 2, 7);
    hash_input(4)(a, b)
}

/// Integer work (counts, prefix sums, indices): the same bits everywhere.
const EXACT: Check = Check::Bound { relative: 0.0, reason: "integers: counts, prefix sums and indices" };
const fn hash(
    name: &'static str,
    twin: Twin,
    count: Count,
    reads: &'static [Buf],
    writes: &'static [Buf],
) -> KernelDef {
    KernelDef {
        check: EXACT,
        label: timing::SELF_HASH,
        variants: worlds(Variants { immediates: true, ..PLAIN }),
        ..KernelDef::new(name, twin, count, reads, writes)
    }
}
/// Each particle's bucket, and the buckets' and their blocks' counts (atomics).
pub static HASH_COUNT: KernelDef = KernelDef {
    accumulates: &[HASH_CELLS, HASH_TOTALS],
    ..hash(
        "hash_count",
        hash_count,
        Count::Particles,
        &[Params, Pos, HASH_CELLS, HASH_TOTALS],
        &[HASH_CELLS, HASH_TOTALS],
    )
};
/// The blocks' totals' exclusive prefix: each block's offset (one workgroup).
pub static HASH_SCAN_TOP: KernelDef = KernelDef {
    test_input: Some(after_count),
    ..hash("hash_scan_top", hash_scan_top, Count::Workgroup, &[Params, HASH_TOTALS], &[HASH_TOTALS])
};
/// The counts' inclusive prefix within each block of buckets from its offset: every
/// bucket's end in the whole array.
pub static HASH_SCAN_BLOCKS: KernelDef = KernelDef {
    test_input: Some(after_top),
    ..hash("hash_scan_blocks", hash_scan_blocks, Count::HashBlocks, &[Params, HASH_CELLS, HASH_TOTALS], &[HASH_CELLS])
};
/// Every particle's position and slot word into its bucket's range, in any order
/// (atomics), each bucket's word moved to its start: checked bucket by bucket as sets.
pub static HASH_SCATTER: KernelDef = KernelDef {
    test_input: Some(after_scan),
    check: Check::Own(
        "every_self_collision_kernel_matches_its_twin_and_a_rollout_through_the_contacts_follows_the_cpu",
    ),
    ..hash(
        "hash_scatter",
        hash_scatter,
        Count::Particles,
        &[Params, Pos, Vel, HASH_CELLS],
        &[VEL_COPY, HASH_CELLS, HASH_SLOTS],
    )
};
/// The response's check: a gather over the contacts, in fixed point.
const RESPONSE: Check = Check::Bound {
    relative: 2e-5,
    reason: "a gather over the contacts with divisions and square roots, truncated to fixed point \
             (a last-bit difference moves a push by t / 65536 at most; exact on lavapipe)",
};
/// The response: every particle pushed out of its close candidates, into the other
/// position buffer.
pub static SELF_COLLIDE: KernelDef = KernelDef {
    check: RESPONSE,
    variants: worlds(Variants { immediates: true, ..PLAIN }),
    pure: &[PosOut],
    label: timing::SELF_COLLIDE,
    test_input: Some(built_hash),
    cloths: Cloths::Grid,
    on_mesh: OnMesh::Kernel(&SELF_COLLIDE_MESH),
    with_friction: Some(&SELF_COLLIDE_FRICTION),
    ..KernelDef::new(
        "self_collide",
        self_collide,
        Count::Pairs,
        &[Params, Pos, Vel, HASH_CELLS, HASH_SLOTS],
        &[PosOut, Vel],
    )
};
/// [`SELF_COLLIDE`] with Coulomb friction at its contacts (the contacts' velocities from
/// the copy in aux0 that `hash_scatter` writes): the recipe's response where the
/// parameters have Coulomb's coefficients.
pub static SELF_COLLIDE_FRICTION: KernelDef = KernelDef {
    check: RESPONSE,
    variants: worlds(Variants { immediates: true, ..PLAIN }),
    pure: &[PosOut],
    label: timing::SELF_COLLIDE,
    test_input: Some(built_hash),
    cloths: Cloths::Grid,
    on_mesh: OnMesh::Kernel(&SELF_COLLIDE_MESH_FRICTION),
    ..KernelDef::new(
        "self_collide_friction",
        self_collide_friction,
        Count::Pairs,
        &[Params, Pos, Vel, VEL_COPY, HASH_CELLS, HASH_SLOTS],
        &[PosOut, Vel],
    )
};
/// [`SELF_COLLIDE`] on a mesh: pairs of consecutive particles, a particle's neighbours
/// its springs (from the table, for the entries within the thickness).
pub static SELF_COLLIDE_MESH: KernelDef = KernelDef {
    check: RESPONSE,
    variants: worlds(Variants { immediates: true, ..PLAIN }),
    pure: &[PosOut],
    label: timing::SELF_COLLIDE,
    test_input: Some(built_hash),
    cloths: Cloths::Mesh,
    with_friction: Some(&SELF_COLLIDE_MESH_FRICTION),
    ..KernelDef::new(
        "self_collide_mesh",
        self_collide,
        Count::Pairs,
        &[Params, Pos, Vel, Slots, BendSlots, Adjacency, HASH_CELLS, HASH_SLOTS],
        &[PosOut, Vel],
    )
};
/// [`SELF_COLLIDE_MESH`] with Coulomb friction at its contacts ([`SELF_COLLIDE_FRICTION`]'s).
pub static SELF_COLLIDE_MESH_FRICTION: KernelDef = KernelDef {
    check: RESPONSE,
    variants: worlds(Variants { immediates: true, ..PLAIN }),
    pure: &[PosOut],
    label: timing::SELF_COLLIDE,
    test_input: Some(built_hash),
    cloths: Cloths::Mesh,
    ..KernelDef::new(
        "self_collide_mesh_friction",
        self_collide_friction,
        Count::Pairs,
        &[Params, Pos, Vel, Slots, BendSlots, Adjacency, VEL_COPY, HASH_CELLS, HASH_SLOTS],
        &[PosOut, Vel],
    )
};
/// Self-collision's kernels, in recipe order.
pub static SELF_COLLISION: [&KernelDef; 5] =
    [&HASH_COUNT, &HASH_SCAN_TOP, &HASH_SCAN_BLOCKS, &HASH_SCATTER, &SELF_COLLIDE];

/// This family's kernels, in the registry's order ([`super::ALL`]).
pub(super) const ROWS: &[&KernelDef] = &[
    &HASH_COUNT,
    &STRAIN_LIMIT_COUNT,
    &STRAIN_LIMIT_INLINE_COUNT,
    &STRAIN_LIMIT_STRIP_COUNT,
    &HASH_SCAN_TOP,
    &HASH_SCAN_BLOCKS,
    &HASH_SCATTER,
    &SELF_COLLIDE,
    &SELF_COLLIDE_MESH,
    &SELF_COLLIDE_FRICTION,
    &SELF_COLLIDE_MESH_FRICTION,
];
