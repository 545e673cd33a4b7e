//! A batch of worlds on the GPU: the scene's cloth once per world in the same buffers,
//! every kernel dispatched once for all of them.
//!
//! Layout: each per-particle buffer (positions, velocities, forces, normals, the scratch
//! buffers) holds world after world, `np` particles each; the face normals hold a world's
//! faces from twice its first particle (`2·np` faces a world; a mesh of more triangles
//! than twice its vertices is refused). The tables — springs,
//! triangles, adjacency, tethers, colours — are the scene's, one copy for every world:
//! a kernel indexes them by the particle's index within its world. The self-collision's
//! hash tables lie world after world in their scratch buffer, each a whole number of the
//! scan's blocks, and each world's scan starts from its first particle: a world's contacts
//! are found among its own particles.
//!
//! Dispatch: the kernels' `_w` twins ([`ConstantsHome::Worlds`]) find their world in the
//! dispatch's z and its step constants — gravity, wind, damping, drag, the collision
//! margin, the contact's share of friction, the thickness, the grab — in the world's
//! element of the array at [`Buf::ParamsStorage`], rewritten every frame. What the shared
//! tables and the recipe hold must be the same in every world: the spring constants (the
//! stiffnesses and the substep), the integrator and its iterations, the self-collision,
//! Coulomb's coefficients (their uniform block). A batch that varies one of those, a
//! recipe with a kernel that has no `_w` twin yet, or per-substep statistics, is refused
//! in one line naming it.
//!
//! [`Buf::ParamsStorage`]: clothlab_core::layout::Buf::ParamsStorage

use clothlab_core::grid::ClothTopology;
use clothlab_core::scene::Scene;
use clothlab_core::step_params::StepParams;
use clothlab_core::{SimParams, SolverError};

use crate::kernels::{ConstantsHome, Flavor, HostBuffers, KernelRef};
use crate::recipe::{Command, Integration, StatsMode};

/// Refuses a batch of `worlds` of `scene` (cloth `topo`, world 0's) that one recipe and
/// one set of tables cannot run: parameters that differ where the worlds share them, a
/// mesh with more triangles than twice its particles, per-substep statistics, or more
/// worlds than the adapter's largest binding holds (the most that fit named).
pub(crate) fn check_batch(
    scene: &Scene,
    topo: &ClothTopology,
    worlds: &[SimParams],
    stats: StatsMode,
    info: &crate::gpu::EngineInfo,
) -> Result<(), SolverError> {
    // The largest binding: the faces, 2·np a world of 16 bytes, or the contact between
    // triangles' integers or pairs.
    let tri = clothlab_cpu::tri_contact::TriLayout::of(topo);
    let contact = if worlds[0].self_collision.triangles() { 4 * tri.words().max(tri.pair_words()) as u64 } else { 0 };
    let per_world = (32 * topo.num_particles() as u64).max(contact);
    if worlds.len() as u64 * per_world > info.max_binding {
        return Err(SolverError::Unsupported(format!(
            "{} worlds of {} particles need {} MiB buffers; {} binds at most {} MiB: at most {} worlds of this scene",
            worlds.len(),
            topo.num_particles(),
            (worlds.len() as u64 * per_world) >> 20,
            info.adapter,
            info.max_binding >> 20,
            info.max_binding / per_world.max(1)
        )));
    }
    if stats != StatsMode::Off {
        return Err(SolverError::Unsupported(
            "a batch of worlds on the GPU computes no per-substep statistics: leave out --stats".into(),
        ));
    }
    if topo.triangles.len() > 2 * topo.num_particles() {
        return Err(SolverError::Unsupported(format!(
            "a batch of worlds lays out 2 faces a particle; this mesh has {} triangles for {} particles",
            topo.triangles.len(),
            topo.num_particles()
        )));
    }
    let first = &worlds[0];
    // The worlds' hash tables lie one after another, a whole number of the scan's blocks
    // each, in the scratch buffers' four words a particle.
    let np = topo.num_particles();
    let stride = clothlab_cpu::self_collide::hash_blocks(np) as usize * clothlab_core::layout::WORKGROUP as usize;
    if first.self_collision == clothlab_core::SelfCollision::Particles && stride > 4 * np {
        return Err(SolverError::Unsupported(format!(
            "a batch of worlds with self-collision needs 16 particles a world or more; this cloth has {np}"
        )));
    }
    let sp0 = StepParams::new(first, scene, None);
    for (k, p) in worlds.iter().enumerate().skip(1) {
        let shared = |what: &str| {
            SolverError::Unsupported(format!(
                "world {k}: its {what} differs from world 0's, and a GPU batch's worlds share it (vary it on cpu or cpu-par)"
            ))
        };
        if p.substeps != first.substeps || p.dt().to_bits() != first.dt().to_bits() {
            return Err(shared("substep"));
        }
        if Integration::of(p) != Integration::of(first) || p.strain_iterations != first.strain_iterations {
            return Err(shared("integrator or its iterations"));
        }
        if p.self_collision != first.self_collision {
            return Err(shared("self-collision"));
        }
        if clothlab_core::grid::spring_constants(p, topo) != clothlab_core::grid::spring_constants(first, topo) {
            return Err(shared("spring constants (the stiffnesses and the mass: one spring table)"));
        }
        let sp = StepParams::new(p, scene, None);
        if bytemuck::bytes_of(&sp.contact) != bytemuck::bytes_of(&sp0.contact) {
            return Err(shared("Coulomb friction (μs, μk) or VBD's ρ"));
        }
    }
    Ok(())
}

/// The `_w` twin of `k`, or why there is none.
fn in_world(k: KernelRef) -> Result<KernelRef, SolverError> {
    let w = k.def.flavor(Flavor { constants: ConstantsHome::Worlds, ..k.flavor }).with_uses(k.uses);
    if w.flavor.constants != ConstantsHome::Worlds {
        return Err(SolverError::Unsupported(format!(
            "a batch of worlds on the GPU: kernel {} has no world dimension yet (the kernels that have one are listed in docs/worlds.md; cpu and cpu-par run any batch)",
            k.def.name
        )));
    }
    Ok(w)
}

/// A substep's commands and the frame end's for a batch of `envs` worlds: each kernel as
/// its `_w` twin (unchanged for a single run).
pub(crate) fn in_worlds(
    step: Vec<Command>,
    end: Vec<Command>,
    envs: usize,
) -> Result<(Vec<Command>, Vec<Command>), SolverError> {
    if envs == 1 {
        return Ok((step, end));
    }
    let map = |commands: Vec<Command>| -> Result<Vec<Command>, SolverError> {
        commands
            .into_iter()
            .map(|c| {
                Ok(match c {
                    Command::Dispatch(k) => Command::Dispatch(in_world(k)?),
                    Command::Range { kernel, first, count } => {
                        Command::Range { kernel: in_world(kernel)?, first, count }
                    }
                    c => c,
                })
            })
            .collect()
    };
    Ok((map(step)?, map(end)?))
}

/// The buffers a batch starts from, world after world, and its worlds' step constants.
pub(crate) struct Starts {
    /// Every world's state, faces `2·np` a world apart (a single run's as it is).
    pub state: HostBuffers,
    /// Every world's step constants, as the `_w` kernels read them (a single run's: its own).
    pub params: Vec<u8>,
    np: usize,
    envs: usize,
}

impl Starts {
    /// World 0's buffers `state` and constants `sp`, with room for `envs` worlds of `np`
    /// particles.
    pub fn new(state: &HostBuffers, sp: &StepParams, envs: usize, np: usize) -> Self {
        let mut s = Starts { state: state.clone(), params: sp.gpu_bytes().to_vec(), np, envs };
        if envs > 1 {
            s.state.faces.resize(2 * np, [0.0; 4]);
        }
        s
    }

    /// The next world's.
    pub fn push(&mut self, state: &HostBuffers, sp: &StepParams) {
        debug_assert!(self.envs > 1 && state.pos.len() == self.np);
        let s = &mut self.state;
        s.pos.extend_from_slice(&state.pos);
        s.vel.extend_from_slice(&state.vel);
        s.force.extend_from_slice(&state.force);
        s.normal.extend_from_slice(&state.normal);
        let mut faces = state.faces.clone();
        faces.resize(2 * self.np, [0.0; 4]);
        s.faces.extend_from_slice(&faces);
        self.params.extend_from_slice(sp.gpu_bytes());
    }
}
