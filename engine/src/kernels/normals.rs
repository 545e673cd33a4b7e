//! The normals (core::cpu::normals): the faces' and the vertices', gathered or scattered.

use super::*;

fn tri_normals(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::tri_normals(a.exec, &a.topo.triangles, &b.pos, &mut b.faces);
}

/// Adds every vertex's adjacent face normals into its normal (what the naive scatter
/// accumulates; the recipe clears the normals first).
fn add_face_sums(a: &TwinArgs, b: &mut HostBuffers) {
    for (i, n) in b.normal.iter_mut().enumerate() {
        for &t in a.topo.face_slots.row(i).iter().filter(|&&t| t >= 0) {
            let f = b.faces[t as usize];
            n.iter_mut().zip(f).take(3).for_each(|(x, y)| *x += y);
        }
    }
}

fn tri_normals_scatter(a: &TwinArgs, b: &mut HostBuffers) {
    tri_normals(a, b);
    add_face_sums(a, b);
}

/// The naive normals kernel's input: the scatter's sums of the current faces.
fn face_sums_input(a: &TwinArgs, b: &mut HostBuffers) {
    b.normal.iter_mut().for_each(|n| *n = [0.0; 4]);
    add_face_sums(a, b);
}

fn vertex_normals(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::vertex_normals(a.exec, a.p, &a.topo.face_slots, &b.faces, &mut b.normal, &mut b.force);
}

/// Face normals per quad of the grid.
/// A mesh's, per two triangles of the list.
pub static TRI_NORMALS: KernelDef = KernelDef {
    pure: &[Faces],
    variants: worlds(Variants { immediates: true, ..PLAIN }),
    ..KernelDef::new("tri_normals", tri_normals, Count::Quads, &[Params, Pos, Triangles], &[Faces])
};
/// The naive face normals: per triangle, also added to the corners' normals with atomics.
pub static TRI_NORMALS_SCATTER: KernelDef = KernelDef {
    check: SCATTER,
    pure: &[Faces],
    accumulates: &[Normal],
    label: timing::TRI_NORMALS,
    variants: worlds(IMM_F32),
    ..KernelDef::new(
        "tri_normals_scatter",
        tri_normals_scatter,
        Count::Triangles,
        &[Params, Pos, Normal, Triangles],
        &[Faces, Normal],
    )
};
/// Vertex normals gathered from the face normals, and the wind force.
pub static VERTEX_NORMALS: KernelDef = KernelDef {
    check: GATHER,
    pure: &[Normal, Force],
    variants: worlds(Variants { immediates: true, ..PLAIN }),
    ..KernelDef::new(
        "vertex_normals",
        vertex_normals,
        Count::Particles,
        &[Params, Pos, Vel, Faces, FaceSlots, Adjacency, Normal, Force],
        &[Normal, Force],
    )
};
/// The naive vertex normals: the scatter's sums normalised, and the wind force.
pub static VERTEX_NORMALS_NAIVE: KernelDef = KernelDef {
    check: GATHER,
    pure: &[Force],
    label: timing::VERTEX_NORMALS,
    test_input: Some(face_sums_input),
    variants: worlds(Variants { immediates: true, ..PLAIN }),
    ..KernelDef::new(
        "vertex_normals_naive",
        vertex_normals,
        Count::Particles,
        &[Params, Pos, Vel, Faces, FaceSlots, Adjacency, Normal, Force],
        &[Normal, Force],
    )
};

/// This family's kernels, in the registry's order ([`super::ALL`]).
pub(super) const ROWS: &[&KernelDef] = &[&TRI_NORMALS, &TRI_NORMALS_SCATTER, &VERTEX_NORMALS, &VERTEX_NORMALS_NAIVE];
