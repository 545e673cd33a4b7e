//! Vertex Block Descent (core::cpu::vbd): a colour of the sweep, the Chebyshev step.

use super::*;

fn vbd_begin(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::vbd::vbd_begin(a.exec, a.p, &b.force, &b.pos, &b.vel, &mut b.aux);
}

/// One colour of VBD's sweep: particles `first .. first + count` of the colouring's list
/// (`topo.colours.order`, binding [`Buf::Colours`]).
fn vbd_colour(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::vbd::vbd_colour(a.exec, a.p, &a.topo.slots, a.colliders, colour_list(a), &mut b.aux, None);
}

/// The particles of the colouring's list the dispatch's range covers (`first .. first +
/// count`, cut to the list): one colour of VBD's sweep.
pub(super) fn colour_list<'a>(a: &TwinArgs<'a>) -> &'a [u32] {
    let order = &a.topo.colours.order;
    let end = (a.range.0 as usize + a.range.1 as usize).min(order.len());
    &order[(a.range.0 as usize).min(end)..end]
}

/// The Chebyshev step after a sweep, ω the bits of the range's `first`.
fn vbd_accelerate(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::vbd::vbd_accelerate(a.exec, a.p, f32::from_bits(a.range.0), &mut b.aux);
}

fn vbd_finish(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::vbd::vbd_finish(a.exec, a.p, &mut b.pos, &mut b.vel, &b.aux);
}

/// VBD: the predicted velocity v' (aux0; the prediction y = x⁰ + h v'), the substep's
/// start x⁰ (aux1) and the displacement D = h v' (aux2) (core::cpu::vbd::vbd_begin).
pub static VBD_BEGIN: KernelDef = KernelDef {
    label: timing::INTEGRATE,
    pure: &[VBD_PREDICTED, VBD_START, VBD_DISPLACEMENT],
    variants: worlds(Variants { immediates: true, ..PLAIN }),
    ..KernelDef::new("vbd_begin", vbd_begin, Count::Particles, STATE, &[VBD_PREDICTED, VBD_START, VBD_DISPLACEMENT])
};
/// VBD: one colour's Newton steps, each particle of the range of the colouring's list
/// ([`Buf::Colours`]) on its 3 × 3 block over its row of the table, into its
/// displacement (aux2).
pub static VBD_COLOUR: KernelDef = KernelDef {
    check: Check::Bound {
        relative: 2e-5,
        reason: "a gather over the row's springs into a 3 × 3 block, solved by cofactors (one division)",
    },
    label: timing::VBD,
    variants: worlds(Variants { table_image: true, colliders_uniform: true, sdf_image: true, ..PLAIN }),
    immediates: Immediates::Range,
    dispatches: Dispatches::Colours,
    ..KernelDef::new(
        "vbd_colour",
        vbd_colour,
        Count::Range,
        &[
            Params,
            Colours,
            Slots,
            BendSlots,
            Adjacency,
            Table,
            Spheres,
            Boxes,
            Shapes,
            VBD_PREDICTED,
            VBD_START,
            VBD_DISPLACEMENT,
        ],
        &[VBD_DISPLACEMENT],
    )
};
/// VBD: the Chebyshev acceleration after a sweep (`vbd_rho` > 0), ω in the immediates as
/// the bits of the range's `first`, `count` the particles (core::cpu::vbd::vbd_accelerate).
pub static VBD_ACCELERATE: KernelDef = KernelDef {
    label: timing::VBD,
    variants: worlds(PLAIN),
    immediates: Immediates::Range,
    dispatches: Dispatches::Chebyshev,
    ..KernelDef::new(
        "vbd_accelerate",
        vbd_accelerate,
        Count::Range,
        &[Params, VBD_PREDICTED, VBD_START, VBD_DISPLACEMENT, VBD_LAST, VBD_BEFORE],
        &[VBD_DISPLACEMENT, VBD_LAST, VBD_BEFORE],
    )
};
/// VBD: x = x⁰ + D, v = v' + (D − h v')/h, with pins, grab and floor
/// (core::cpu::vbd::vbd_finish).
pub static VBD_FINISH: KernelDef = KernelDef {
    label: timing::INTEGRATE,
    variants: worlds(Variants { immediates: true, ..PLAIN }),
    ..KernelDef::new(
        "vbd_finish",
        vbd_finish,
        Count::Particles,
        &[Params, VBD_PREDICTED, VBD_START, VBD_DISPLACEMENT],
        &[Pos, Vel],
    )
};

/// This family's kernels, in the registry's order ([`super::ALL`]).
pub(super) const ROWS: &[&KernelDef] = &[&VBD_BEGIN, &VBD_COLOUR, &VBD_ACCELERATE, &VBD_FINISH];
