//! Twin of the `stats` kernels: per-substep statistics of the state, the numbers a GPU
//! solver can report every substep without reading the state back.

use super::v3;
use clothlab_core::grid::{Rows, SpringSlot, V4};
pub use clothlab_core::stats::SubstepStats;
use clothlab_core::step_params::StepParams;

/// Particle `i`'s share: the largest strain of the structural springs that start at it
/// (on a grid slots 1 and 3, to its +i and +j neighbours, so that every structural spring
/// is counted once; on a mesh (n = 0) every edge at it, its row's head, which the strain
/// limit holds) and its kinetic energy. `slots` is the whole table.
#[inline]
pub fn particle_stats(i: usize, p: &StepParams, slots: &Rows<SpringSlot>, pos: &[V4], vel: &[V4]) -> [f32; 2] {
    let x = v3(pos[i]);
    let mut strain = 0.0f32;
    let row = slots.row(i);
    let grid = [row[1], row[3]];
    let which: &[SpringSlot] = if p.n == 0 { slots.head(i) } else { &grid };
    for slot in which {
        if slot.neighbor >= 0 {
            strain = strain.max((v3(pos[slot.neighbor as usize]) - x).length() / slot.rest - 1.0);
        }
    }
    let v = v3(vel[i]);
    [strain, 0.5 * super::mass(p, pos[i][3]) * v.dot(v)]
}

/// The statistics of the whole state: the maximum of the strains, and the energies summed
/// in f64 (the reference the GPU reductions are checked against).
pub fn substep_stats(p: &StepParams, slots: &Rows<SpringSlot>, pos: &[V4], vel: &[V4]) -> SubstepStats {
    let (mut max_strain, mut energy) = (0.0f32, 0.0f64);
    for i in 0..pos.len() {
        let [s, e] = particle_stats(i, p, slots, pos, vel);
        max_strain = max_strain.max(s);
        energy += e as f64;
    }
    SubstepStats { max_strain, kinetic_energy: energy as f32 }
}
