//! The adjoint of a substep (clothlab_cpu::adjoint; docs/gradients.md): run on the
//! substep's input after its force is recomputed there, they take the gradient with
//! respect to its output back to its input and add each particle's partials of the
//! parameters ([`Buf::Adjoint`]'s planes).

use super::*;

fn adj_integrate(a: &TwinArgs, b: &mut HostBuffers) {
    b.adjoint_sized(a.topo.num_particles());
    cpu::adjoint::adj_integrate(a.exec, a.p, a.colliders, &b.pos, &b.vel, &b.force, &mut b.adjoint);
}

fn adj_springs(a: &TwinArgs, b: &mut HostBuffers) {
    b.adjoint_sized(a.topo.num_particles());
    cpu::adjoint::adj_springs(a.exec, a.topo.mesh.is_none(), &a.topo.slots, &b.pos, &b.vel, &mut b.adjoint);
}

fn adj_strain_back(a: &TwinArgs, b: &mut HostBuffers) {
    b.adjoint_sized(a.topo.num_particles());
    let (slots, tethers) = (&a.topo.slots, &a.topo.tethers);
    cpu::adjoint::adj_strain_back(a.exec, a.p, slots, tethers, &b.pos, &b.aux[0], &mut b.adjoint);
}

fn adj_strain_gather(a: &TwinArgs, b: &mut HostBuffers) {
    b.adjoint_sized(a.topo.num_particles());
    cpu::adjoint::adj_strain_gather(a.exec, a.p, &a.topo.slots, &b.pos, &b.aux[0], &mut b.adjoint);
}

/// A kernel check's adjoint: every plane random in ±1 (seeded), so that what a kernel
/// reads (the gradients it starts from, its neighbours' force gradients) and what it adds
/// to (the partials) all show.
fn random_adjoint(a: &TwinArgs, b: &mut HostBuffers) {
    let np = a.topo.num_particles();
    b.adjoint_sized(np);
    let mut rng = 0x9e37_79b9_7f4a_7c15u64;
    for v in b.adjoint.iter_mut().flatten() {
        rng = rng.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        *v = ((rng >> 40) as f32 / (1u64 << 23) as f32) - 1.0;
    }
    // The tethers' shares name a pinned particle (every fifth) or none, so that a pin's
    // gather finds some.
    let pin = b.pos.iter().position(|x| x[3] == 0.0).map_or(-1.0, |k| k as f32);
    for plane in 8..10 {
        for (k, v) in b.adjoint[plane * np..(plane + 1) * np].iter_mut().enumerate() {
            v[3] = if k % 5 == 0 { pin } else { -1.0 };
        }
    }
}

/// The adjoint's per-particle work: a few dozen operations and, at a sphere, a division
/// by the distance from its centre.
const ADJ_ELEMENT: Check = Check::Bound {
    relative: 2e-5,
    reason: "a few dozen f32 operations per particle, a sphere's taken back through a division by its distance",
};

/// The adjoint of `integrate` (Verlet, the floor) and `collide`'s still spheres.
pub static ADJ_INTEGRATE: KernelDef = KernelDef {
    check: ADJ_ELEMENT,
    label: timing::ADJOINT,
    variants: Variants { immediates: true, ..PLAIN },
    test_input: Some(random_adjoint),
    ..KernelDef::new(
        "adj_integrate",
        adj_integrate,
        Count::Particles,
        &[Params, Pos, Vel, Force, Spheres, Adjoint],
        &[Adjoint],
    )
};
/// The adjoint of the spring gather, a gather itself (no atomics).
pub static ADJ_SPRINGS: KernelDef = KernelDef {
    check: GATHER,
    label: timing::ADJOINT,
    variants: Variants { immediates: true, ..PLAIN },
    test_input: Some(random_adjoint),
    ..KernelDef::new(
        "adj_springs",
        adj_springs,
        Count::Particles,
        &[Params, Pos, Vel, Slots, BendSlots, Adjacency, Adjoint],
        &[Adjoint],
    )
};

/// The first half of a strain pass's adjoint: each point's gradient back through its
/// tethers, the tethers' shares of their pins.
pub static ADJ_STRAIN_BACK: KernelDef = KernelDef {
    check: GATHER,
    label: timing::ADJOINT,
    variants: Variants { immediates: true, ..PLAIN },
    test_input: Some(random_adjoint),
    ..KernelDef::new(
        "adj_strain_back",
        adj_strain_back,
        Count::Particles,
        &[Params, Pos, Tethers, Slots, BendSlots, Adjacency, STRAIN_COUNTS, Adjoint],
        &[Adjoint],
    )
};
/// The second half: the springs' corrections taken back from either end (a gather), a
/// pin's tethers' shares gathered from every particle.
pub static ADJ_STRAIN_GATHER: KernelDef = KernelDef {
    check: GATHER,
    label: timing::ADJOINT,
    variants: Variants { immediates: true, ..PLAIN },
    test_input: Some(random_adjoint),
    ..KernelDef::new(
        "adj_strain_gather",
        adj_strain_gather,
        Count::Particles,
        &[Params, Pos, Slots, BendSlots, Adjacency, STRAIN_COUNTS, Adjoint],
        &[Adjoint],
    )
};

/// The adjoint's kernels: run only where a solver has the adjoint's planes
/// (`crate::solver::has_adjoint`).
pub const ADJOINT_KERNELS: [&KernelDef; 4] = [&ADJ_INTEGRATE, &ADJ_SPRINGS, &ADJ_STRAIN_BACK, &ADJ_STRAIN_GATHER];

/// This family's kernels, in the registry's order ([`super::ALL`]).
pub(super) const ROWS: &[&KernelDef] = &[&ADJ_INTEGRATE, &ADJ_SPRINGS, &ADJ_STRAIN_BACK, &ADJ_STRAIN_GATHER];
