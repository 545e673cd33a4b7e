//! The force kernels, the integration and the colliders (core::cpu::forces, springs,
//! integrate, collide): separate, fused as clothlab fuses them, and as the thesis did.

use super::*;

fn forces(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::forces(a.exec, a.p, &b.pos, &b.vel, &mut b.force);
}

fn springs(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::springs(a.exec, &a.topo.slots, &b.pos, &b.vel, &mut b.force);
}

fn forces_springs(a: &TwinArgs, b: &mut HostBuffers) {
    forces(a, b);
    springs(a, b);
}

/// The wind of the faces around each particle, computed from the positions as
/// `tri_normals` and `vertex_normals` compute it, then `forces_springs` from it: the force
/// the three kernels leave, without the face and vertex normals (the kernel keeps those in
/// registers).
fn forces_springs_wind(a: &TwinArgs, b: &mut HostBuffers) {
    let mut faces = vec![[0.0; 4]; a.topo.triangles.len()];
    cpu::tri_normals(a.exec, &a.topo.triangles, &b.pos, &mut faces);
    let mut normal = vec![[0.0; 4]; b.pos.len()];
    cpu::vertex_normals(a.exec, a.p, &a.topo.face_slots, &faces, &mut normal, &mut b.force);
    forces_springs(a, b);
}

fn springs_scatter(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::springs_scatter(&a.topo.springs, &b.pos, &b.vel, &mut b.force);
}

fn integrate(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::integrate(a.exec, a.p, &b.force, &mut b.pos, &mut b.vel);
}

fn pins(a: &TwinArgs, b: &mut HostBuffers) {
    let poses: &[PinPose] = bytemuck::cast_slice(&b.pin_poses);
    clothlab_core::pins::drive(&a.topo.pins.slots, poses, a.substep, &mut b.pos, &mut b.vel);
}

fn collide(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::collide(a.exec, a.p, a.colliders, &mut b.pos, &mut b.vel);
}

fn integrate_collide(a: &TwinArgs, b: &mut HostBuffers) {
    integrate(a, b);
    collide(a, b);
}

/// The fused kernel keeps the total force in a register: the force buffer is left as the
/// springs left it.
fn forces_integrate_collide(a: &TwinArgs, b: &mut HostBuffers) {
    let springs = b.force.clone();
    forces(a, b);
    integrate_collide(a, b);
    b.force = springs;
}

/// Gravity and drag into the force buffer (added to the wind force already there).
pub static FORCES: KernelDef = KernelDef {
    variants: worlds(Variants { immediates: true, ..PLAIN }),
    ..KernelDef::new("forces", forces, Count::Particles, &[Params, Pos, Vel, Force], &[Force])
};
/// The spring gather per particle over its 12-slot table.
pub static SPRINGS: KernelDef = KernelDef {
    check: GATHER,
    variants: worlds(IMM_TEX),
    ..KernelDef::new("springs", springs, Count::Particles, TABLE, &[Force])
};
/// The naive spring scatter: one invocation per spring, forces added with atomics.
pub static SPRINGS_SCATTER: KernelDef = KernelDef {
    check: SCATTER,
    label: timing::SPRINGS,
    variants: worlds(IMM_F32),
    ..KernelDef::new(
        "springs_scatter",
        springs_scatter,
        Count::Springs,
        &[Params, Pos, Vel, Force, Springs, SpringsB],
        &[Force],
    )
};
/// `forces` fused into the spring gather, four particles of a row per invocation.
pub static FORCES_SPRINGS: KernelDef = KernelDef {
    check: GATHER,
    label: timing::FORCES_SPRINGS,
    variants: worlds(BLOCKED),
    ..KernelDef::new("forces_springs", forces_springs, Count::Blocks, TABLE, &[Force])
};
/// `forces_springs` with the wind of the faces around each particle computed from the
/// positions the gather loads anyway (`normals=frame`): the force buffer is only written.
pub static FORCES_SPRINGS_WIND: KernelDef = KernelDef {
    check: WIND_GATHER,
    pure: &[Force],
    label: timing::FORCES_SPRINGS_WIND,
    variants: worlds(BLOCKED),
    ..KernelDef::new(
        "forces_springs_wind",
        forces_springs_wind,
        Count::Blocks,
        &[Params, Pos, Vel, Slots, BendSlots, Adjacency, Interior, Table, Triangles, FaceSlots],
        &[Force],
    )
};
/// Verlet, pins, the grab and the floor.
pub static INTEGRATE: KernelDef = KernelDef {
    variants: worlds(Variants { immediates: true, ..PLAIN }),
    ..KernelDef::new("integrate", integrate, Count::Particles, STATE, &[Pos, Vel])
};
/// Moving pins to their poses at the substep's end (`clothlab_core::pins`).
pub static PINS: KernelDef = KernelDef {
    variants: worlds(PLAIN),
    immediates: Immediates::Substep,
    label: timing::PINS,
    ..KernelDef::new("pins", pins, Count::Pins, &[Params, Pos, Vel, Pins, PinPoses], &[Pos, Vel])
};
/// Spheres, boxes and bodies.
pub static COLLIDE: KernelDef = KernelDef {
    variants: worlds(IMM_CU),
    ..KernelDef::new("collide", collide, Count::Particles, COLLIDERS, &[Pos, Vel])
};
/// `integrate` and `collide` fused: each particle loaded and stored once.
pub static INTEGRATE_COLLIDE: KernelDef = KernelDef {
    label: timing::INTEGRATE_COLLIDE,
    variants: worlds(IMM_CU),
    ..KernelDef::new(
        "integrate_collide",
        integrate_collide,
        Count::Particles,
        &[Params, Pos, Vel, Force, Spheres, Boxes, Shapes],
        &[Pos, Vel],
    )
};
/// `forces`, `integrate` and `collide` fused: the thesis's optimized "Verlet" kernel. The
/// total force is used, not stored (the normals kernel rewrites the force buffer later in
/// the substep, so nothing reads it).
pub static FORCES_INTEGRATE_COLLIDE: KernelDef = KernelDef {
    label: timing::FORCES_INTEGRATE_COLLIDE,
    variants: worlds(IMM_CU),
    ..KernelDef::new(
        "forces_integrate_collide",
        forces_integrate_collide,
        Count::Particles,
        &[Params, Pos, Vel, Force, Spheres, Boxes, Shapes],
        &[Pos, Vel],
    )
};

/// This family's kernels, in the registry's order ([`super::ALL`]).
pub(super) const ROWS: &[&KernelDef] = &[
    &FORCES,
    &SPRINGS,
    &SPRINGS_SCATTER,
    &FORCES_SPRINGS,
    &FORCES_SPRINGS_WIND,
    &INTEGRATE,
    &PINS,
    &COLLIDE,
    &INTEGRATE_COLLIDE,
    &FORCES_INTEGRATE_COLLIDE,
];
