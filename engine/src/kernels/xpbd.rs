//! XPBD (core::cpu::integrators): the grid's 12 coloured passes and a mesh's pass over a
//! range of its springs.

use super::*;

/// The twins of the 12 XPBD passes (core::cpu::XPBD_PASSES).
macro_rules! xpbd_twins {
    ($($name:ident = $k:expr),*) => {
        $(fn $name(a: &TwinArgs, b: &mut HostBuffers) {
            cpu::xpbd_pass(a.p, &a.topo.slots, $k, &mut b.pos, &mut b.vel, &mut b.aux);
        })*
    };
}
xpbd_twins!(
    xpbd_0 = 0,
    xpbd_1 = 1,
    xpbd_2 = 2,
    xpbd_3 = 3,
    xpbd_4 = 4,
    xpbd_5 = 5,
    xpbd_6 = 6,
    xpbd_7 = 7,
    xpbd_8 = 8,
    xpbd_9 = 9,
    xpbd_10 = 10,
    xpbd_11 = 11
);

/// A mesh's XPBD pass over springs `first .. first + count`, λ of spring k in word k of
/// aux0 then aux1 (as the kernel keeps them).
fn xpbd_mesh(a: &TwinArgs, b: &mut HostBuffers) {
    let np = b.pos.len();
    let mut lambda: Vec<f32> = b.aux[0].iter().chain(&b.aux[1]).flatten().copied().collect();
    let (first, count) = (a.range.0 as usize, a.range.1 as usize);
    let end = (first + count).min(a.topo.springs.len());
    cpu::xpbd_mesh_pass(a.exec, a.p, &a.topo.springs, first.min(end)..end, &mut b.pos, &mut b.vel, &mut lambda);
    for (k, l) in lambda.chunks_exact(4).enumerate() {
        let v = [l[0], l[1], l[2], l[3]];
        if k < np { b.aux[0][k] = v } else { b.aux[1][k - np] = v }
    }
}

/// One XPBD pass: the springs of one direction and colour (core::cpu::XPBD_PASSES),
/// both ends moved in place, their velocities with them.
/// On a mesh the mesh's passes ([`XPBD_MESH`]) run in the place of an iteration's first
/// pass (`cpu::XPBD_ORDER`), and the other passes are left out.
const fn xpbd(name: &'static str, twin: Twin, pass: usize) -> KernelDef {
    KernelDef {
        check: GATHER,
        label: timing::XPBD,
        variants: worlds(IMM_TEX),
        cloths: Cloths::Grid,
        on_mesh: if pass == cpu::XPBD_ORDER[0] { OnMesh::Kernel(&XPBD_MESH) } else { OnMesh::Nothing },
        ..KernelDef::new(
            name,
            twin,
            Count::Particles,
            &[Params, Pos, Vel, Slots, BendSlots, Adjacency, Table, LAMBDA[0], LAMBDA[1]],
            &[Pos, Vel, LAMBDA[0], LAMBDA[1]],
        )
    }
}
/// The 12 passes of one XPBD iteration, in order.
pub static XPBD: [KernelDef; 12] = [
    xpbd("xpbd_0", xpbd_0, 0),
    xpbd("xpbd_1", xpbd_1, 1),
    xpbd("xpbd_2", xpbd_2, 2),
    xpbd("xpbd_3", xpbd_3, 3),
    xpbd("xpbd_4", xpbd_4, 4),
    xpbd("xpbd_5", xpbd_5, 5),
    xpbd("xpbd_6", xpbd_6, 6),
    xpbd("xpbd_7", xpbd_7, 7),
    xpbd("xpbd_8", xpbd_8, 8),
    xpbd("xpbd_9", xpbd_9, 9),
    xpbd("xpbd_10", xpbd_10, 10),
    xpbd("xpbd_11", xpbd_11, 11),
];
/// One XPBD pass of a mesh: a range of its spring list sorted by pass
/// (`MeshTables::xpbd_passes`), λ per spring in aux0 and aux1.
pub static XPBD_MESH: KernelDef = KernelDef {
    check: GATHER,
    label: timing::XPBD,
    variants: worlds(PLAIN),
    immediates: Immediates::Range,
    cloths: Cloths::Mesh,
    dispatches: Dispatches::MeshPasses,
    ..KernelDef::new(
        "xpbd_mesh",
        xpbd_mesh,
        Count::Range,
        &[Params, Pos, Vel, Springs, SpringsB, LAMBDA[0], LAMBDA[1]],
        &[Pos, Vel, LAMBDA[0], LAMBDA[1]],
    )
};

/// This family's kernels, in the registry's order ([`super::ALL`]).
pub(super) const ROWS: &[&KernelDef] = &[
    &XPBD[0], &XPBD[1], &XPBD[2], &XPBD[3], &XPBD[4], &XPBD[5], &XPBD[6], &XPBD[7], &XPBD[8], &XPBD[9], &XPBD[10],
    &XPBD[11], &XPBD_MESH,
];
