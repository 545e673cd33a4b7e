//! Recipes: the ordered dispatches of one substep for each variant, as data. Every GPU
//! backend executes the same recipe, so two backends running one variant differ only in
//! the API and how it is driven.

use clothlab_core::timing::{FORCES_SPRINGS, INTEGRATE_COLLIDE, KernelId};

/// Which formulation of the step runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Variant {
    /// One dispatch per kernel, scatter with atomics, a submission per substep.
    Naive,
    /// Fused kernels, gathers, one submission per frame.
    Optimized,
}

/// What a dispatch runs over.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Count {
    /// One invocation per particle.
    Particles,
    /// One per [`BLOCK`] consecutive particles of a row (`n · ⌈n / BLOCK⌉`).
    Blocks,
    /// One per quad of the grid (two triangles).
    Quads,
    /// One per spring of the flat list.
    Springs,
    /// One per triangle.
    Triangles,
    /// One workgroup (a final reduction).
    Workgroup,
}

/// One dispatch of a recipe.
#[derive(Debug, Clone, Copy)]
pub struct Dispatch {
    /// Kernel name in [`crate::KERNELS`].
    pub kernel: &'static str,
    /// Timing label.
    pub label: &'static str,
    /// What it runs over.
    pub count: Count,
    /// Zero the normal accumulators first (naive normals).
    pub clear_normal: bool,
    /// Writes positions to the other buffer of the pair (strain limit's ping-pong).
    pub flips: bool,
    /// Takes the substep's index in immediates (the statistics kernels).
    pub substep_push: bool,
}

const fn d(kernel: &'static str, label: &'static str, count: Count) -> Dispatch {
    Dispatch { kernel, label, count, clear_normal: false, flips: false, substep_push: false }
}

/// The name of `kernel` without its `_imm` (immediates) and `_tex` (table in an image)
/// suffixes: the kernel whose CPU twin it shares.
pub fn base_name(kernel: &str) -> &str {
    kernel.trim_end_matches("_imm").trim_end_matches("_tex")
}

/// The dispatch that runs `kernel` alone (kernel tests, `clothlab validate`).
pub fn dispatch_for(kernel: &'static str) -> Dispatch {
    let base = base_name(kernel);
    let count = if base.starts_with("springs_scatter") {
        Count::Springs
    } else if base == "forces_springs" || base == "strain_limit" {
        Count::Blocks
    } else if base == "tri_normals" {
        Count::Quads
    } else if base.starts_with("tri_normals") {
        Count::Triangles
    } else {
        Count::Particles
    };
    Dispatch {
        kernel,
        label: kernel,
        count,
        clear_normal: base.starts_with("tri_normals_scatter"),
        flips: base == "strain_limit",
        substep_push: false,
    }
}

/// The `<kernel><suffix>` twin where there is one, else `kernel`.
fn twin(kernel: &'static str, suffix: &str) -> &'static str {
    crate::kernel(&format!("{kernel}{suffix}")).map_or(kernel, |k| k.name)
}

/// What the adapter offers that the recipes use.
#[derive(Debug, Clone, Copy)]
pub struct Caps {
    /// `atomic<f32>` add in storage buffers.
    pub float_atomics: bool,
    /// Immediates (push constants) large enough for the step constants.
    pub immediates: bool,
    /// Read the spring table from a sampled image (`<kernel>_tex` twins) instead of
    /// storage buffers (Vulkan only: the thesis's texture memory).
    pub table_image: bool,
}

/// The dispatches of one substep for `variant` with `strain_passes` strain passes; the
/// naive scatters use float atomics where the adapter has them, the optimized kernels
/// read the step constants from immediates where it has those.
pub fn recipe(variant: Variant, strain_passes: u32, caps: Caps) -> Vec<Dispatch> {
    let float_atomics = caps.float_atomics;
    let strain = Dispatch { flips: true, ..d("strain_limit", "strain_limit", Count::Blocks) };
    let mut r = Vec::new();
    match variant {
        Variant::Naive => {
            r.push(d("forces", KernelId::Forces.name(), Count::Particles));
            let (springs, normals) = if float_atomics {
                ("springs_scatter_f32", "tri_normals_scatter_f32")
            } else {
                ("springs_scatter", "tri_normals_scatter")
            };
            r.push(d(springs, KernelId::Springs.name(), Count::Springs));
            r.push(d("integrate", KernelId::Integrate.name(), Count::Particles));
            r.push(d("collide", KernelId::Collide.name(), Count::Particles));
            r.extend((0..strain_passes).map(|_| strain));
            r.push(Dispatch { clear_normal: true, ..d(normals, "tri_normals", Count::Triangles) });
            r.push(d("vertex_normals_naive", KernelId::VertexNormals.name(), Count::Particles));
        }
        Variant::Optimized => {
            r.push(d("forces_springs", FORCES_SPRINGS, Count::Blocks));
            r.push(d("integrate_collide", INTEGRATE_COLLIDE, Count::Particles));
            r.extend((0..strain_passes).map(|_| strain));
            r.push(d("tri_normals", KernelId::TriNormals.name(), Count::Quads));
            r.push(d("vertex_normals", KernelId::VertexNormals.name(), Count::Particles));
            for dsp in &mut r {
                if caps.table_image {
                    dsp.kernel = twin(dsp.kernel, "_tex");
                }
                if caps.immediates {
                    dsp.kernel = twin(dsp.kernel, "_imm");
                }
            }
        }
    }
    r
}

/// How a substep's statistics (max strain, kinetic energy) are reduced on the GPU.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StatsMode {
    /// Not computed.
    #[default]
    Off,
    /// Every invocation adds into the substep's entry with atomics (`stats_atomic`).
    Atomics,
    /// Subgroup and workgroup reductions, one partial per workgroup, then one workgroup
    /// folds the partials (`stats` + `stats_reduce`): no atomics.
    Subgroups,
}

/// The dispatches that compute a substep's statistics at its end.
pub fn stats_dispatches(mode: StatsMode, caps: Caps) -> Vec<Dispatch> {
    let push = |kernel, count| Dispatch { substep_push: true, ..d(kernel, kernel, count) };
    match mode {
        StatsMode::Off => Vec::new(),
        StatsMode::Atomics => {
            let k = if caps.float_atomics { "stats_atomic_f32" } else { "stats_atomic" };
            vec![Dispatch { label: "stats_atomic", ..push(k, Count::Particles) }]
        }
        StatsMode::Subgroups => vec![push("stats", Count::Particles), push("stats_reduce", Count::Workgroup)],
    }
}

/// The spring table as one image of rgba32uint texels (`shared/table_tex.wgsl`): slot s of
/// particle i at texel 12 i + s, [`TABLE_WIDTH`] texels a row. Returns the texels (4 words
/// each, row-major, the last row padded with empty slots) and the image's height.
pub fn table_texels(topo: &clothlab_core::ClothTopology) -> (Vec<[u32; 4]>, u32) {
    let count = topo.slots.len();
    let height = count.div_ceil(TABLE_WIDTH as usize).max(1);
    let mut texels = vec![[u32::MAX, 0, 0, 0]; height * TABLE_WIDTH as usize];
    for (t, s) in texels.iter_mut().zip(&topo.slots) {
        *t = [s.neighbor as u32, s.rest.to_bits(), s.ks.to_bits(), s.kd.to_bits()];
    }
    (texels, height as u32)
}

/// Particles per invocation of the blocked kernels (`BLOCK` in shared/types.wgsl).
pub const BLOCK: u32 = 4;

/// Texels per row of the spring-table image (`TABLE_WIDTH` in shared/table_tex.wgsl).
pub const TABLE_WIDTH: u32 = 4096;

/// Workgroups of 64 for `count` invocations, as a 2-D grid (x ≤ 65535).
pub fn groups(count: u32) -> (u32, u32) {
    let g = count.div_ceil(64).max(1);
    let x = g.min(65535);
    (x, g.div_ceil(x))
}

impl Count {
    /// How many invocations this is on `topo`.
    pub fn of(self, topo: &clothlab_core::ClothTopology) -> u32 {
        match self {
            Count::Particles => topo.num_particles() as u32,
            Count::Blocks => topo.n * topo.n.div_ceil(BLOCK),
            Count::Quads => (topo.triangles.len() / 2) as u32,
            Count::Springs => topo.springs.len() as u32,
            Count::Triangles => topo.triangles.len() as u32,
            Count::Workgroup => 64,
        }
    }
}

/// The distinct kernels of a recipe, in order.
pub fn kernels_of(recipe: &[Dispatch]) -> Vec<&'static str> {
    let mut v: Vec<&'static str> = Vec::new();
    for d in recipe {
        if !v.contains(&d.kernel) {
            v.push(d.kernel);
        }
    }
    v
}

/// A buffer a kernel only writes (so it is poisoned with NaN before a kernel test).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Output {
    /// The other buffer of the position pair.
    PosOut,
    /// Face normals.
    Faces,
    /// Vertex normals.
    Normal,
    /// The force buffer.
    Force,
}

/// The pure outputs of `kernel`.
pub fn pure_outputs(kernel: &str) -> &'static [Output] {
    match base_name(kernel) {
        "strain_limit" => &[Output::PosOut],
        "tri_normals" | "tri_normals_scatter" | "tri_normals_scatter_f32" => &[Output::Faces],
        "vertex_normals" => &[Output::Normal, Output::Force],
        "vertex_normals_naive" => &[Output::Force],
        _ => &[],
    }
}

/// Records the per-dispatch GPU times of one submission: `ticks` holds a begin and an end
/// timestamp per entry of `labels`; every `per_substep` dispatches also make a substep
/// row. Returns the submission's span in ns (first begin to last end).
pub fn record_times(
    timer: &mut clothlab_core::TimingRecorder,
    labels: &[&'static str],
    ticks: &[u64],
    period_ns: f64,
    per_substep: usize,
) -> f64 {
    let mut substep_ns = 0.0;
    for (k, label) in labels.iter().enumerate() {
        let ns = ticks[2 * k + 1].saturating_sub(ticks[2 * k]) as f64 * period_ns;
        timer.record(label, ns);
        substep_ns += ns;
        if (k + 1) % per_substep.max(1) == 0 {
            timer.record(clothlab_core::timing::SUBSTEP, substep_ns);
            substep_ns = 0.0;
        }
    }
    match (ticks.first(), ticks.get(2 * labels.len().max(1) - 1)) {
        (Some(a), Some(b)) => b.saturating_sub(*a) as f64 * period_ns,
        _ => 0.0,
    }
}

/// The spring table as the shaders read it: slots `0..STRAIN_SLOTS` of every particle,
/// then the remaining (bend) slots of every particle, so that each part stays within
/// the 128 MiB a storage binding may span on many adapters up to n = 1024.
pub fn split_slots(
    topo: &clothlab_core::ClothTopology,
) -> (Vec<clothlab_core::SpringSlot>, Vec<clothlab_core::SpringSlot>) {
    use clothlab_core::grid::{SLOTS, STRAIN_SLOTS};
    let mut strain = Vec::with_capacity(topo.num_particles() * STRAIN_SLOTS);
    let mut bend = Vec::with_capacity(topo.num_particles() * (SLOTS - STRAIN_SLOTS));
    for p in topo.slots.chunks_exact(SLOTS) {
        strain.extend_from_slice(&p[..STRAIN_SLOTS]);
        bend.extend_from_slice(&p[STRAIN_SLOTS..]);
    }
    (strain, bend)
}

/// The flat spring list in two halves (bindings 7 and 15), for the same reason.
pub fn spring_halves(springs: &[clothlab_core::Spring]) -> (&[clothlab_core::Spring], &[clothlab_core::Spring]) {
    springs.split_at(springs.len() / 2)
}

/// The buffers a frame's dispatches read and write (the tables, written only between
/// frames, are left out), as bits; the position pair by physical buffer.
pub mod res {
    /// Position buffer 0 of the pair.
    pub const POS0: u32 = 1 << 0;
    /// Position buffer 1 of the pair.
    pub const POS1: u32 = 1 << 1;
    /// Previous positions.
    pub const PREV: u32 = 1 << 2;
    /// Forces.
    pub const FORCE: u32 = 1 << 3;
    /// Vertex normals.
    pub const NORMAL: u32 = 1 << 4;
    /// Face normals.
    pub const FACES: u32 = 1 << 5;
    /// Step constants.
    pub const PARAMS: u32 = 1 << 6;
    /// The per-substep statistics.
    pub const STATS: u32 = 1 << 7;
    /// The statistics' per-workgroup partials.
    pub const PARTIALS: u32 = 1 << 8;
    /// Everything.
    pub const ALL: u32 = (1 << 9) - 1;
}

/// What `kernel` reads and writes when the current positions are `pos[cur]` (atomic
/// read-modify-writes count as both). Errs on the side of reading more.
pub fn access(kernel: &str, cur: usize) -> (u32, u32) {
    use res::*;
    let (pos, pos_out) = if cur == 0 { (POS0, POS1) } else { (POS1, POS0) };
    let state = PARAMS | pos | PREV;
    match base_name(kernel).trim_end_matches("_f32") {
        "forces" | "springs" | "forces_springs" => (state | FORCE, FORCE),
        "springs_scatter" => (state | FORCE, FORCE),
        "integrate" | "integrate_collide" => (state | FORCE, pos | PREV),
        "collide" => (state, pos | PREV),
        "strain_limit" => (PARAMS | pos, pos_out),
        "tri_normals" => (PARAMS | pos, FACES),
        "tri_normals_scatter" => (PARAMS | pos | NORMAL, NORMAL),
        "vertex_normals" | "vertex_normals_naive" => (state | FACES | NORMAL | FORCE, NORMAL | FORCE),
        "stats" => (state, PARTIALS),
        "stats_atomic" => (state | STATS, STATS),
        "stats_reduce" => (PARAMS | PARTIALS | STATS, STATS),
        // Unknown: depends on everything.
        _ => (ALL, ALL),
    }
}

/// Tracks what was read and written since the last barrier, so that a recorder places a
/// barrier only before an access that depends on an earlier one: a read or write of
/// something written (read-after-write, write-after-write) or a write of something read
/// (write-after-read). A global memory barrier clears both sets.
#[derive(Debug, Clone, Copy, Default)]
pub struct Hazards {
    read: u32,
    written: u32,
}

impl Hazards {
    /// Whether an access reading `reads` and writing `writes` must wait for a barrier.
    pub fn conflicts(&self, reads: u32, writes: u32) -> bool {
        (reads | writes) & self.written != 0 || writes & self.read != 0
    }

    /// Notes an access (after any barrier it needed).
    pub fn add(&mut self, reads: u32, writes: u32) {
        self.read |= reads;
        self.written |= writes;
    }

    /// Notes a barrier.
    pub fn clear(&mut self) {
        *self = Self::default();
    }

    /// Notes an access the tracker cannot see (an upload): everything is suspect.
    pub fn dirty(&mut self) {
        self.written = res::ALL;
    }

    /// Notes dispatch `d` at parity `cur`; returns whether a barrier must come before
    /// its normal clear (naive normals) and whether one must come before the dispatch.
    pub fn dispatch(&mut self, d: &Dispatch, cur: usize) -> (bool, bool) {
        let mut before_clear = false;
        if d.clear_normal {
            before_clear = self.conflicts(0, res::NORMAL);
            if before_clear {
                self.clear();
            }
            self.add(0, res::NORMAL);
        }
        let (r, w) = access(d.kernel, cur);
        let before = self.conflicts(r, w);
        if before {
            self.clear();
        }
        self.add(r, w);
        (before_clear, before)
    }

    /// The number of barriers `dispatches` need from parity `cur`.
    pub fn plan(&mut self, dispatches: &[Dispatch], mut cur: usize) -> usize {
        let mut count = 0;
        for d in dispatches {
            let (a, b) = self.dispatch(d, cur);
            count += a as usize + b as usize;
            if d.flips {
                cur ^= 1;
            }
        }
        count
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CAPS: Caps = Caps { float_atomics: false, immediates: true, table_image: false };

    fn barriers_per_substep(r: &[Dispatch]) -> usize {
        // Two substeps, counted in the second (the first also pays for the frame start).
        let two: Vec<Dispatch> = r.iter().chain(r).copied().collect();
        let mut h = Hazards::default();
        let first = h.plan(r, 0);
        assert!(first >= 1);
        // Parity after one substep: flipped once per strain pass.
        let cur = r.iter().filter(|d| d.flips).count() % 2;
        h.plan(&two[r.len()..], cur)
    }

    #[test]
    fn every_dependent_dispatch_gets_a_barrier_and_no_other() {
        // Optimized: each of its five kernels reads what the one before wrote.
        let opt = recipe(Variant::Optimized, 1, CAPS);
        assert_eq!(barriers_per_substep(&opt), opt.len());
        // Statistics read only the positions: they need no barrier after the normals,
        // and the reduction's barrier also covers the next substep's force write, so
        // they cost no barrier at all.
        let mut with_stats = opt.clone();
        with_stats.extend(stats_dispatches(StatsMode::Subgroups, CAPS));
        assert_eq!(barriers_per_substep(&with_stats), opt.len());
        let mut with_atomics = opt.clone();
        with_atomics.extend(stats_dispatches(StatsMode::Atomics, CAPS));
        // stats_atomic writes the substep's own entry: the next substep's forces depend
        // on the normals' force write, so one barrier covers both.
        assert_eq!(barriers_per_substep(&with_atomics), opt.len());
        // Naive: every dispatch waits for the one before; the normal clear needs none (the
        // normals were last read several barriers ago), the scatter after it does.
        let naive = recipe(Variant::Naive, 1, CAPS);
        assert_eq!(barriers_per_substep(&naive), naive.len());
        // Two strain passes: the second reads the first's output.
        let two_passes = recipe(Variant::Optimized, 2, CAPS);
        assert_eq!(barriers_per_substep(&two_passes), two_passes.len());
    }

    #[test]
    fn a_read_after_a_write_always_waits() {
        let mut h = Hazards::default();
        assert!(!h.conflicts(res::POS0, res::FORCE));
        h.add(res::POS0, res::FORCE);
        assert!(h.conflicts(res::FORCE, 0), "read after write");
        assert!(h.conflicts(0, res::FORCE), "write after write");
        assert!(h.conflicts(0, res::POS0), "write after read");
        assert!(!h.conflicts(res::POS0 | res::PREV, res::FACES), "reads of unwritten buffers");
        h.clear();
        assert!(!h.conflicts(res::FORCE, res::FORCE));
        h.dirty();
        assert!(h.conflicts(res::PREV, 0));
    }
}
