//! The spring tables as the GPU backends upload them, and the per-dispatch timing both
//! record.

use clothlab_core::grid::{SLOTS, STRAIN_SLOTS};
use clothlab_core::layout::TABLE_WIDTH;
use clothlab_core::{ClothTopology, Spring, SpringSlot};

/// The bodies' distance fields as one 3-D image (`sdf=image`, `shared/sdf_image.wgsl`):
/// `(values, [width, height, depth])`, the grids stacked along z in body order, each from
/// the image's corner in x and y (the texels beyond a narrower grid hold a large value:
/// they are never inside a grid's bounds, which the kernels check first); x fastest.
/// With no bodies, one texel (the binding needs an image).
pub fn sdf_texels(bodies: &[clothlab_core::sdf::Body]) -> (Vec<f32>, [u32; 3]) {
    let w = bodies.iter().map(|b| b.sdf.dims[0]).max().unwrap_or(1);
    let h = bodies.iter().map(|b| b.sdf.dims[1]).max().unwrap_or(1);
    let d = bodies.iter().map(|b| b.sdf.dims[2]).sum::<u32>().max(1);
    let mut texels = vec![1e3f32; (w * h * d) as usize];
    let mut z0 = 0;
    for b in bodies {
        let [nx, ny, nz] = b.sdf.dims;
        for k in 0..nz {
            for j in 0..ny {
                let src = ((k * ny + j) * nx) as usize;
                let dst = (((z0 + k) * h + j) * w) as usize;
                texels[dst..dst + nx as usize].copy_from_slice(&b.sdf.values[src..src + nx as usize]);
            }
        }
        z0 += nz;
    }
    (texels, [w, h, d])
}

/// The spring table as one image of rgba32uint texels (`shared/table_tex.wgsl`): entry k
/// of the table ([`clothlab_core::grid::Rows::entries`]: slot s of a grid's particle i at
/// k = 12 i + s, a mesh's rows one after another) at texel k, [`TABLE_WIDTH`] texels a
/// row. Returns the texels (4 words each, row-major, the last row padded with empty
/// slots) and the image's height.
pub fn table_texels(topo: &ClothTopology) -> (Vec<[u32; 4]>, u32) {
    let entries = topo.slots.entries();
    let height = entries.len().div_ceil(TABLE_WIDTH as usize).max(1);
    let mut texels = vec![[u32::MAX, 0, 0, 0]; height * TABLE_WIDTH as usize];
    for (t, s) in texels.iter_mut().zip(entries) {
        *t = [s.neighbor as u32, s.rest.to_bits(), s.ks.to_bits(), s.kd.to_bits()];
    }
    (texels, height as u32)
}

/// The spring table as the shaders read it, in two bindings so that each part stays
/// within the 128 MiB a storage binding may span on many adapters. A grid's: slots
/// `0..STRAIN_SLOTS` of every particle, then the remaining (bend) slots of every particle
/// (up to n = 1024). A mesh's: its rows one after another, the first half of them (by
/// entries, whole rows: [`mesh_split`]) in the first binding, the rest in the second
/// (an empty slot if none; up to about 1.4 M vertices of 12 springs).
pub fn split_slots(topo: &ClothTopology) -> (Vec<SpringSlot>, Vec<SpringSlot>) {
    if topo.slots.width().is_none() {
        let (a, b) = topo.slots.entries().split_at(mesh_split(topo) as usize);
        return (a.to_vec(), if b.is_empty() { vec![SpringSlot::EMPTY] } else { b.to_vec() });
    }
    let mut strain = Vec::with_capacity(topo.num_particles() * STRAIN_SLOTS);
    let mut bend = Vec::with_capacity(topo.num_particles() * (SLOTS - STRAIN_SLOTS));
    for p in topo.slots.entries().chunks_exact(SLOTS) {
        strain.extend_from_slice(&p[..STRAIN_SLOTS]);
        bend.extend_from_slice(&p[STRAIN_SLOTS..]);
    }
    (strain, bend)
}

/// The face slots as the shaders read them: a grid's six a particle, a mesh's rows one
/// after another.
pub fn face_flat(topo: &ClothTopology) -> &[i32] {
    topo.face_slots.entries()
}

/// Where a mesh's table is split between its two bindings ([`split_slots`]): the start of
/// the first row (after row 0) that starts at or past half of the entries, or the end.
pub fn mesh_split(topo: &ClothTopology) -> u32 {
    let total = topo.slots.entries().len() as u32;
    (1..topo.num_particles())
        .filter_map(|i| topo.slots.csr_bounds(i).map(|(first, _)| first))
        .find(|&first| 2 * first >= total)
        .unwrap_or(total)
}

/// The compressed rows' bounds ([`clothlab_core::layout::Buf::Adjacency`]): per particle
/// `(first slot, head length, first face slot, slot count | BINDING_2)` — the first slot
/// counted within the binding that holds the row ([`split_slots`]), `BINDING_2` set where
/// that is the second — and one past the last `(0, 0, end of the faces, split)`, the
/// split being the second binding's first entry in the whole table (the image's texel
/// of its entry 0). For a grid (fixed rows, which its kernels compute) one zero element.
pub fn adjacency(topo: &ClothTopology) -> Vec<[u32; 4]> {
    let np = topo.num_particles();
    if topo.slots.width().is_some() {
        return vec![[0; 4]];
    }
    let split = mesh_split(topo);
    let mut rows: Vec<[u32; 4]> = (0..np)
        .map(|i| {
            let r = topo.slots.range(i);
            let head = topo.slots.head(i).len() as u32;
            let (face, _) = topo.face_slots.csr_bounds(i).unwrap_or_default();
            let (first, count) = (r.start as u32, r.len() as u32);
            match first >= split && count > 0 {
                true => [first - split, head, face, count | BINDING_2],
                false => [first, head, face, count],
            }
        })
        .collect();
    let (faces, _) = topo.face_slots.csr_bounds(np).unwrap_or_default();
    rows.push([0, 0, faces, split]);
    rows
}

/// The flag of [`adjacency`]'s fourth word: the row lies in the table's second binding.
pub const BINDING_2: u32 = 1 << 31;

/// The flat spring list in two halves (bindings 7 and 15), for the same reason.
pub fn spring_halves(springs: &[Spring]) -> (&[Spring], &[Spring]) {
    springs.split_at(springs.len() / 2)
}

/// Records the GPU times of one frame: `ticks` holds a begin and an end timestamp per
/// entry of `labels`; consecutive entries of one label make one sample, and every
/// `per_substep` dispatches also make a substep row. The `per_end` dispatches after the
/// `substeps` substeps run once per frame (recipe::frame_end): each is recorded as its
/// time per substep (divided by `substeps`), and their sum divided alike is added to every
/// substep sample, so that a substep row is what the frame costs per substep. An end that
/// was not timed in full (the query limit) is left out. With temporal blocking the recipe
/// ran once per `group` substeps: each recording's times are shared by its `group`
/// substeps (1 otherwise). Returns the span in ns (first begin to last end).
pub fn record_times(
    timer: &mut clothlab_core::TimingRecorder,
    labels: &[&'static str],
    ticks: &[u64],
    period_ns: f64,
    per_substep: usize,
    per_end: usize,
    (substeps, group): (u32, u32),
) -> f64 {
    // With temporal blocking the recipe ran once per `group` substeps: each recording's
    // times are shared by its substeps.
    let group = group.max(1);
    let recordings = substeps.div_ceil(group);
    let ns_of = |k: usize| ticks[2 * k + 1].saturating_sub(ticks[2 * k]) as f64 * period_ns / f64::from(group);
    let in_substeps = labels.len().min(recordings as usize * per_substep);
    let end = &labels[in_substeps..];
    let per = f64::from(recordings.max(1));
    let timed_end = per_end > 0 && end.len() == per_end;
    let share = if timed_end { (in_substeps..labels.len()).map(ns_of).sum::<f64>() / per } else { 0.0 };
    let mut substep_ns = share;
    // Consecutive dispatches of one label (the hash's three or four kernels, XPBD's
    // passes, the CG loop) make one sample: a row is that work's time per substep, not per
    // dispatch.
    let mut run_ns = 0.0;
    for (k, label) in labels[..in_substeps].iter().enumerate() {
        let ns = ns_of(k);
        run_ns += ns;
        substep_ns += ns;
        let end_of_substep = (k + 1) % per_substep.max(1) == 0;
        if end_of_substep || labels.get(k + 1) != Some(label) {
            timer.record(label, run_ns);
            run_ns = 0.0;
        }
        if end_of_substep {
            timer.record(clothlab_core::timing::SUBSTEP, substep_ns);
            substep_ns = share;
        }
    }
    if timed_end {
        for (k, label) in end.iter().enumerate() {
            timer.record(label, ns_of(in_substeps + k) / per);
        }
    }
    match (ticks.first(), ticks.get(2 * labels.len().max(1) - 1)) {
        (Some(a), Some(b)) => b.saturating_sub(*a) as f64 * period_ns,
        _ => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clothlab_core::TimingRecorder;
    use clothlab_core::timing::SUBSTEP;

    /// A mesh's rows as the shaders find them: through `adjacency`, in the binding its
    /// flag names, and in the image at `table_index` — each the topology's row, its head
    /// the row's edges; the split whole rows, near half the entries.
    #[test]
    fn a_meshs_rows_read_back_from_the_two_bindings_and_the_image() {
        for name in ["mesh-fan.toml", "mesh-cape.toml", "two-cloths.toml"] {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes").join(name);
            let file = clothlab_core::SceneFile::load(&path).unwrap();
            let (_, topo) = clothlab_core::build(&file.scene, &file.params).unwrap();
            let (first, second) = split_slots(&topo);
            let adj = adjacency(&topo);
            let np = topo.num_particles();
            let split = adj[np][3];
            let total = topo.slots.entries().len();
            assert_eq!(first.len(), split as usize, "{name}");
            assert!(first.len() >= total / 2 && first.len() < total / 2 + 200, "{name}: split {split} of {total}");
            let (texels, _) = table_texels(&topo);
            for (i, &[start, head, _, w]) in adj[..np].iter().enumerate() {
                let (count, in_second) = ((w & !BINDING_2) as usize, w & BINDING_2 != 0);
                let binding = if in_second { &second } else { &first };
                let row = &binding[start as usize..start as usize + count];
                assert_eq!(row, topo.slots.row(i), "{name}: row {i}");
                assert_eq!(head as usize, topo.slots.head(i).len(), "{name}: row {i}");
                let at = start + if in_second { split } else { 0 };
                let texel = texels[at as usize];
                assert_eq!(texel[0] as i32, row[0].neighbor, "{name}: row {i} in the image");
            }
        }
    }

    #[test]
    fn a_frame_end_adds_its_share_to_every_substep_and_its_rows_per_substep() {
        // Two substeps of (a 10 ns, b 20 ns), then an end of c 40 ns and d 60 ns: each
        // substep costs 30 + 100 / 2 = 80 ns of the frame, c 20 and d 30 per substep.
        let labels = ["a", "b", "a", "b", "c", "d"];
        let ns = [10u64, 20, 10, 20, 40, 60];
        let mut ticks = Vec::new();
        let mut t = 1000;
        for d in ns {
            ticks.extend([t, t + d]);
            t += d + 5;
        }
        let mut timer = TimingRecorder::default();
        let span = record_times(&mut timer, &labels, &ticks, 1.0, 2, 2, (2, 1));
        let table = timer.table();
        let median = |l: &str| table.get(l).map(|r| r.median_ns).unwrap();
        assert_eq!(median(SUBSTEP), 80.0);
        assert_eq!((median("a"), median("b"), median("c"), median("d")), (10.0, 20.0, 20.0, 30.0));
        assert_eq!(span, (t - 5 - 1000) as f64);
        // An end cut short by the query limit is left out, not counted as a substep.
        let mut timer = TimingRecorder::default();
        record_times(&mut timer, &labels[..5], &ticks[..10], 1.0, 2, 2, (2, 1));
        let table = timer.table();
        assert_eq!(table.get(SUBSTEP).map(|r| (r.median_ns, r.samples)), Some((30.0, 2)));
        assert!(table.get("c").is_none());
    }
}
