//! The spring tables as the GPU backends upload them, and the per-dispatch timing both
//! record.

use clothlab_core::grid::{SLOTS, STRAIN_SLOTS};
use clothlab_core::layout::TABLE_WIDTH;
use clothlab_core::{ClothTopology, Spring, SpringSlot};

/// The spring table as one image of rgba32uint texels (`shared/table_tex.wgsl`): slot s of
/// particle i at texel 12 i + s, [`TABLE_WIDTH`] texels a row. Returns the texels (4 words
/// each, row-major, the last row padded with empty slots) and the image's height.
pub fn table_texels(topo: &ClothTopology) -> (Vec<[u32; 4]>, u32) {
    let count = topo.slots.len();
    let height = count.div_ceil(TABLE_WIDTH as usize).max(1);
    let mut texels = vec![[u32::MAX, 0, 0, 0]; height * TABLE_WIDTH as usize];
    for (t, s) in texels.iter_mut().zip(&topo.slots) {
        *t = [s.neighbor as u32, s.rest.to_bits(), s.ks.to_bits(), s.kd.to_bits()];
    }
    (texels, height as u32)
}

/// The spring table as the shaders read it: slots `0..STRAIN_SLOTS` of every particle,
/// then the remaining (bend) slots of every particle, so that each part stays within
/// the 128 MiB a storage binding may span on many adapters up to n = 1024.
pub fn split_slots(topo: &ClothTopology) -> (Vec<SpringSlot>, Vec<SpringSlot>) {
    let mut strain = Vec::with_capacity(topo.num_particles() * STRAIN_SLOTS);
    let mut bend = Vec::with_capacity(topo.num_particles() * (SLOTS - STRAIN_SLOTS));
    for p in topo.slots.chunks_exact(SLOTS) {
        strain.extend_from_slice(&p[..STRAIN_SLOTS]);
        bend.extend_from_slice(&p[STRAIN_SLOTS..]);
    }
    (strain, bend)
}

/// The flat spring list in two halves (bindings 7 and 15), for the same reason.
pub fn spring_halves(springs: &[Spring]) -> (&[Spring], &[Spring]) {
    springs.split_at(springs.len() / 2)
}

/// Records the GPU times of one submission: `ticks` holds a begin and an end timestamp
/// per entry of `labels`; consecutive entries of one label make one sample, and every
/// `per_substep` dispatches also make a substep row. Returns the submission's span in ns (first begin to last end).
pub fn record_times(
    timer: &mut clothlab_core::TimingRecorder,
    labels: &[&'static str],
    ticks: &[u64],
    period_ns: f64,
    per_substep: usize,
) -> f64 {
    let mut substep_ns = 0.0;
    // Consecutive dispatches of one label (the hash's six kernels, XPBD's passes, the CG
    // loop) make one sample: a row is that work's time per substep, not per dispatch.
    let mut run_ns = 0.0;
    for (k, label) in labels.iter().enumerate() {
        let ns = ticks[2 * k + 1].saturating_sub(ticks[2 * k]) as f64 * period_ns;
        run_ns += ns;
        substep_ns += ns;
        let end_of_substep = (k + 1) % per_substep.max(1) == 0;
        if end_of_substep || labels.get(k + 1) != Some(label) {
            timer.record(label, run_ns);
            run_ns = 0.0;
        }
        if end_of_substep {
            timer.record(clothlab_core::timing::SUBSTEP, substep_ns);
            substep_ns = 0.0;
        }
    }
    match (ticks.first(), ticks.get(2 * labels.len().max(1) - 1)) {
        (Some(a), Some(b)) => b.saturating_sub(*a) as f64 * period_ns,
        _ => 0.0,
    }
}
