//! Kernel ids and the per-kernel timing table every solver reports.

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};

// The timing labels: the one list of them. The kernel registry
// (clothlab_engine::kernels) labels its rows with these constants, the CPU solvers
// time their sweeps with them, and the timing tables group rows by them; a test there checks
// that every row's label is one of [`KERNEL_LABELS`].

/// Label of the moving pins put at their poses (`pins`).
pub const PINS: &str = "pins";
/// Label of gravity, drag and the wind's force (`forces`).
pub const FORCES: &str = "forces";
/// Label of the spring forces (`springs`: gathered, or scattered with atomics).
pub const SPRINGS: &str = "springs";
/// Label of an integrator's own step (Verlet's, Euler's, an RK stage, implicit's finish).
pub const INTEGRATE: &str = "integrate";
/// Label of the spheres and boxes (`collide`).
pub const COLLIDE: &str = "collide";
/// Label of the Provot strain limit and the tethers (one label for all passes of a substep).
pub const STRAIN_LIMIT: &str = "strain_limit";
/// Label of the face normals.
pub const TRI_NORMALS: &str = "tri_normals";
/// Label of the vertex normals and the wind force.
pub const VERTEX_NORMALS: &str = "vertex_normals";
/// Label of XPBD's constraint passes.
pub const XPBD: &str = "xpbd";
/// Label of Vertex Block Descent's colour sweeps (its prediction and finish are
/// [`INTEGRATE`]).
pub const VBD: &str = "vbd";
/// Label of implicit Euler's conjugate gradients (every CG kernel and reduction).
pub const CG: &str = "cg";
/// Label of the GPU statistics (`--stats`: the reductions and their fold).
pub const STATS: &str = "stats";
/// Label of the CPU solvers' fused `forces` + `springs` sweep.
pub const FORCES_SPRINGS: &str = "forces+springs";
/// Label of the forces + springs gather that computes the wind of its faces itself
/// (`normals=frame`).
pub const FORCES_SPRINGS_WIND: &str = "forces+springs+wind";
/// Label of the CPU solvers' fused `integrate` + `collide` sweep.
pub const INTEGRATE_COLLIDE: &str = "integrate+collide";
/// Label of the thesis's fused `forces` + `integrate` + `collide` kernel.
pub const FORCES_INTEGRATE_COLLIDE: &str = "forces+integrate+collide";
/// Label of the CPU solvers' fused sweep: every kernel of a Verlet substep, row by row.
pub const FUSED_STEP: &str = "fused substep";
/// Label of the tiled substep (`fusion=tile`): a Verlet substep in one dispatch over
/// workgroup-memory tiles, and its velocities put into place after it.
pub const SUBSTEP_TILE: &str = "substep tile";
/// Label of the whole-substep row.
pub const SUBSTEP: &str = "substep";
/// Self-collision's hash build (count, prefix sum, scatter; without the count where it
/// is fused into the strain limit's last pass: [`STRAIN_LIMIT_COUNT`]).
pub const SELF_HASH: &str = "self_hash";
/// Label of the strain limit's last pass fused with self-collision's hash count.
pub const STRAIN_LIMIT_COUNT: &str = "strain_limit+hash_count";
/// Self-collision's response.
pub const SELF_COLLIDE: &str = "self_collide";
/// The contact between triangles' bounds: the pairs within reach at the substep's start
/// and each vertex's bound on its motion (core::tri_contact).
pub const TRI_BOUNDS: &str = "tri_bounds";
/// The contact between triangles' response: the pairs closer than the thickness pushed
/// apart, then every vertex's motion clamped to its bound.
pub const TRI_CONTACT: &str = "tri_contact";
/// Label of a substep's adjoint (`grad=True`: the adjoint kernels, docs/gradients.md).
pub const ADJOINT: &str = "adjoint";
/// Every label a kernel (a registry row or a CPU sweep) is timed under, in step order.
pub const KERNEL_LABELS: [&str; 24] = [
    TRI_BOUNDS,
    PINS,
    FORCES,
    SPRINGS,
    FORCES_SPRINGS,
    FORCES_SPRINGS_WIND,
    FORCES_INTEGRATE_COLLIDE,
    INTEGRATE,
    CG,
    XPBD,
    VBD,
    COLLIDE,
    INTEGRATE_COLLIDE,
    STRAIN_LIMIT,
    STRAIN_LIMIT_COUNT,
    SELF_HASH,
    SELF_COLLIDE,
    TRI_CONTACT,
    TRI_NORMALS,
    VERTEX_NORMALS,
    STATS,
    FUSED_STEP,
    SUBSTEP_TILE,
    ADJOINT,
];
/// Label of the whole-frame row (all substeps of a frame).
pub const FRAME: &str = "frame";
/// Label of a GPU solver's CPU time per frame spent recording its commands (wgpu: encoding
/// the passes and finishing; Vulkan: vkCmd* calls into the command buffers).
pub const CPU_RECORD: &str = "cpu record";
/// Label of a GPU solver's CPU time per frame spent submitting (wgpu: `Queue::submit`;
/// Vulkan: `vkQueueSubmit`).
pub const CPU_SUBMIT: &str = "cpu submit";

/// Statistics of one label's samples.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TimingRow {
    /// Kernel name, [`SUBSTEP`] or [`FRAME`].
    pub label: String,
    /// Number of samples the statistics are over.
    pub samples: usize,
    /// Median, ns.
    pub median_ns: f64,
    /// Minimum, ns.
    pub min_ns: f64,
    /// Maximum, ns.
    pub max_ns: f64,
}

/// Per-kernel timings: one row per label, in the order labels were first recorded.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct KernelTimings {
    /// The rows.
    pub rows: Vec<TimingRow>,
}

impl KernelTimings {
    /// The row for `label`, if any samples were recorded.
    pub fn get(&self, label: &str) -> Option<&TimingRow> {
        self.rows.iter().find(|r| r.label == label)
    }
}

/// Collects timing samples per label, keeping the most recent `capacity` of each.
#[derive(Debug, Clone)]
pub struct TimingRecorder {
    capacity: usize,
    series: Vec<(String, VecDeque<f64>)>,
}

impl Default for TimingRecorder {
    fn default() -> Self {
        Self::new(4096)
    }
}

impl TimingRecorder {
    /// A recorder keeping at most `capacity` samples per label (at least 1).
    pub fn new(capacity: usize) -> Self {
        Self { capacity: capacity.max(1), series: Vec::new() }
    }

    /// Adds one sample, in nanoseconds.
    pub fn record(&mut self, label: &str, ns: f64) {
        let idx = match self.series.iter().position(|(l, _)| l == label) {
            Some(i) => i,
            None => {
                self.series.push((label.to_owned(), VecDeque::new()));
                self.series.len() - 1
            }
        };
        let q = &mut self.series[idx].1;
        if q.len() == self.capacity {
            q.pop_front();
        }
        q.push_back(ns);
    }

    /// Forgets every sample.
    pub fn clear(&mut self) {
        self.series.clear();
    }

    /// Median, min and max of each label.
    pub fn table(&self) -> KernelTimings {
        let rows = self
            .series
            .iter()
            .filter_map(|(label, q)| TimingRow::from_samples(label, q.iter().copied().collect()))
            .collect();
        KernelTimings { rows }
    }
}

impl TimingRow {
    /// Median, min and max of `samples` (ns); `None` when there are none.
    pub fn from_samples(label: &str, mut samples: Vec<f64>) -> Option<Self> {
        if samples.is_empty() {
            return None;
        }
        samples.sort_by(f64::total_cmp);
        let mid = samples.len() / 2;
        let median = if samples.len() % 2 == 1 { samples[mid] } else { 0.5 * (samples[mid - 1] + samples[mid]) };
        Some(TimingRow {
            label: label.to_owned(),
            samples: samples.len(),
            median_ns: median,
            min_ns: samples[0],
            max_ns: samples[samples.len() - 1],
        })
    }
}

/// Nanoseconds since `t`, as the timing tables take them.
pub fn elapsed_ns(t: std::time::Instant) -> f64 {
    t.elapsed().as_nanos() as f64
}

/// What the API-overhead micro-benchmarks of `clothlab bench` measure, the same on every
/// API: see [`OverheadRow`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OverheadPlan {
    /// Measured repetitions of each benchmark (after `warmup` unmeasured ones).
    pub samples: usize,
    /// Unmeasured repetitions first (pipelines, caches, clocks).
    pub warmup: usize,
    /// Chain lengths k: k dependent dispatches of one workgroup, a barrier between each two.
    pub chain: Vec<u32>,
    /// Buffer sizes for the upload and readback latencies, bytes.
    pub bytes: Vec<u64>,
}

impl Default for OverheadPlan {
    fn default() -> Self {
        Self { samples: 100, warmup: 10, chain: vec![1, 2, 4, 8, 16, 32, 64], bytes: vec![4 << 10, 1 << 20, 16 << 20] }
    }
}

/// Benchmark names of [`OverheadRow::bench`].
pub mod overhead {
    /// An empty command buffer submitted, then waited for (CPU clock).
    pub const EMPTY_SUBMIT: &str = "empty submit";
    /// k dependent one-workgroup dispatches (param = k).
    pub const CHAIN: &str = "chain";
    /// Host → device copy of `param` bytes, until the GPU has it (CPU clock).
    pub const UPLOAD: &str = "upload";
    /// Device → host copy of `param` bytes, until the host has it (CPU clock).
    pub const READBACK: &str = "readback";
    /// Clock label: CPU time recording the commands.
    pub const CPU_RECORD: &str = "cpu record";
    /// Clock label: CPU time from submit until the GPU is done (wall).
    pub const CPU_SUBMIT_WAIT: &str = "cpu submit+wait";
    /// Clock label: whole round trip on the CPU clock (upload, readback, empty submit).
    pub const CPU_TOTAL: &str = "cpu total";
    /// Clock label: GPU time from timestamps (first dispatch begin to last end).
    pub const GPU: &str = "gpu";

    use std::time::Instant;

    use super::{OverheadPlan, OverheadRecorder, OverheadRow, elapsed_ns};

    /// One run of a dispatch chain, timed by the API's side.
    #[derive(Debug, Clone, Copy, PartialEq)]
    pub struct ChainSample {
        /// CPU time recording the commands, ns.
        pub record_ns: f64,
        /// CPU time from submit until the GPU is done, ns.
        pub submit_wait_ns: f64,
        /// GPU time from the timestamps around the chain, ns (None without timestamps).
        pub gpu_ns: Option<f64>,
    }

    /// What an API does for the overhead benchmarks; [`measure`] repeats, times and checks
    /// it the same way on every API, so the wgpu and Vulkan columns differ only in the
    /// calls behind these methods.
    pub trait OverheadTarget {
        /// The API's error.
        type Error;
        /// An error for a failed check.
        fn error(what: &'static str, reason: String) -> Self::Error;
        /// Submits an empty command buffer and waits for it.
        fn empty_submit(&mut self) -> Result<(), Self::Error>;
        /// Zeroes the chain buffer, records `k` dependent dispatches of the `chain` kernel
        /// on it (a barrier between each two), submits and waits.
        fn chain(&mut self, k: u32) -> Result<ChainSample, Self::Error>;
        /// The chain buffer after the last chain.
        fn chain_values(&mut self) -> Result<Vec<u32>, Self::Error>;
        /// Makes the buffers for transfers of `bytes` bytes (a multiple of 4).
        fn prepare_transfers(&mut self, bytes: u64) -> Result<(), Self::Error>;
        /// Copies `data` into a device-local buffer; returns once the GPU has it.
        fn upload(&mut self, data: &[u8]) -> Result<(), Self::Error>;
        /// Copies that buffer back into `out`; returns once `out` holds it.
        fn readback(&mut self, out: &mut [u8]) -> Result<(), Self::Error>;
    }

    /// Runs every benchmark of `plan` on `target`: `plan.warmup` unmeasured repetitions,
    /// then `plan.samples` measured ones each. Every result is checked — after a chain of
    /// k every element holds k, a readback returns what was uploaded — so that no API is
    /// fast by skipping work.
    pub fn measure<T: OverheadTarget>(target: &mut T, plan: &OverheadPlan) -> Result<Vec<OverheadRow>, T::Error> {
        let mut rec = OverheadRecorder::default();
        let measured = |i: usize| i >= plan.warmup;
        let reps = plan.warmup + plan.samples;
        for i in 0..reps {
            let t = Instant::now();
            target.empty_submit()?;
            if measured(i) {
                rec.record(EMPTY_SUBMIT, 0, CPU_TOTAL, elapsed_ns(t));
            }
        }
        for &k in &plan.chain {
            for i in 0..reps {
                let s = target.chain(k)?;
                if measured(i) {
                    rec.record(CHAIN, k as u64, CPU_RECORD, s.record_ns);
                    rec.record(CHAIN, k as u64, CPU_SUBMIT_WAIT, s.submit_wait_ns);
                    if let Some(g) = s.gpu_ns {
                        rec.record(CHAIN, k as u64, GPU, g);
                    }
                }
            }
            let got = target.chain_values()?;
            if let Some(bad) = got.iter().find(|&&x| x != k).or(got.is_empty().then_some(&0)) {
                return Err(T::error("checking the chain", format!("after {k} dispatches an element holds {bad}")));
            }
        }
        for &bytes in &plan.bytes {
            let size = bytes.max(4).next_multiple_of(4);
            let pattern: Vec<u8> = (0..size).map(|i| (i * 7 % 251) as u8).collect();
            let mut out = vec![0u8; size as usize];
            target.prepare_transfers(size)?;
            for i in 0..reps {
                let t = Instant::now();
                target.upload(&pattern)?;
                let upload = elapsed_ns(t);
                let t = Instant::now();
                target.readback(&mut out)?;
                let readback = elapsed_ns(t);
                if measured(i) {
                    rec.record(UPLOAD, bytes, CPU_TOTAL, upload);
                    rec.record(READBACK, bytes, CPU_TOTAL, readback);
                }
            }
            if out != pattern {
                return Err(T::error("checking the readback", format!("{bytes} bytes came back different")));
            }
        }
        Ok(rec.rows())
    }
}

/// One API-overhead measurement: benchmark, its parameter, the clock, and the statistics
/// of the samples (`stats.label` is the clock label).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OverheadRow {
    /// One of the names in [`overhead`].
    pub bench: String,
    /// k for the chain, bytes for upload/readback, 0 otherwise.
    pub param: u64,
    /// Median, min, max and sample count, ns.
    pub stats: TimingRow,
}

/// Collects overhead samples per (bench, param, clock) and turns them into rows.
#[derive(Debug, Default)]
pub struct OverheadRecorder {
    series: Vec<(String, u64, String, Vec<f64>)>,
}

impl OverheadRecorder {
    /// Adds one sample, ns.
    pub fn record(&mut self, bench: &str, param: u64, clock: &str, ns: f64) {
        match self.series.iter_mut().find(|(b, p, c, _)| b == bench && *p == param && c == clock) {
            Some(s) => s.3.push(ns),
            None => self.series.push((bench.to_owned(), param, clock.to_owned(), vec![ns])),
        }
    }

    /// The rows, in the order first recorded.
    pub fn rows(self) -> Vec<OverheadRow> {
        self.series
            .into_iter()
            .filter_map(|(bench, param, clock, v)| {
                TimingRow::from_samples(&clock, v).map(|stats| OverheadRow { bench, param, stats })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::overhead::{ChainSample, OverheadTarget};
    use super::*;

    /// An API stand-in whose chain can drop a dispatch and whose readback can lose a byte.
    struct Fake {
        chain: Vec<u32>,
        skip_dispatch: bool,
        lose_byte: bool,
        memory: Vec<u8>,
    }

    impl OverheadTarget for Fake {
        type Error = String;
        fn error(what: &'static str, reason: String) -> String {
            format!("{what}: {reason}")
        }
        fn empty_submit(&mut self) -> Result<(), String> {
            Ok(())
        }
        fn chain(&mut self, k: u32) -> Result<ChainSample, String> {
            let done = if self.skip_dispatch { k - 1 } else { k };
            self.chain = vec![done; 64];
            Ok(ChainSample { record_ns: k as f64, submit_wait_ns: 10.0 * k as f64, gpu_ns: Some(5.0 * k as f64) })
        }
        fn chain_values(&mut self) -> Result<Vec<u32>, String> {
            Ok(self.chain.clone())
        }
        fn prepare_transfers(&mut self, bytes: u64) -> Result<(), String> {
            self.memory = vec![0; bytes as usize];
            Ok(())
        }
        fn upload(&mut self, data: &[u8]) -> Result<(), String> {
            self.memory.copy_from_slice(data);
            Ok(())
        }
        fn readback(&mut self, out: &mut [u8]) -> Result<(), String> {
            out.copy_from_slice(&self.memory);
            if self.lose_byte {
                out[1] ^= 1;
            }
            Ok(())
        }
    }

    #[test]
    fn the_overhead_driver_times_every_benchmark_and_catches_skipped_work() {
        let plan = OverheadPlan { samples: 4, warmup: 2, chain: vec![1, 8], bytes: vec![10] };
        let fake = |skip_dispatch, lose_byte| Fake { chain: vec![], skip_dispatch, lose_byte, memory: vec![] };
        let rows = overhead::measure(&mut fake(false, false), &plan).unwrap();
        // empty submit, 3 clocks × 2 chain lengths, upload and readback of one size.
        assert_eq!(rows.len(), 1 + 6 + 2);
        assert!(rows.iter().all(|r| r.stats.samples == 4), "warm-up repetitions are not samples");
        let gpu8 = rows.iter().find(|r| r.bench == overhead::CHAIN && r.param == 8 && r.stats.label == "gpu").unwrap();
        assert_eq!(gpu8.stats.median_ns, 40.0);
        // 10 bytes are sent as 12 (whole u32 words) but reported under the size asked for.
        assert!(rows.iter().any(|r| r.bench == overhead::UPLOAD && r.param == 10));
        let e = overhead::measure(&mut fake(true, false), &plan).unwrap_err();
        assert!(e.contains("after 1 dispatches an element holds 0"), "{e}");
        let e = overhead::measure(&mut fake(false, true), &plan).unwrap_err();
        assert!(e.contains("came back different"), "{e}");
    }

    #[test]
    fn median_min_max_and_capacity() {
        let mut r = TimingRecorder::new(4);
        for x in [9.0, 1.0, 5.0, 3.0, 7.0] {
            r.record("k", x);
        }
        // 9.0 fell out of the window of 4: samples 1, 3, 5, 7.
        let row = r.table().get("k").cloned().unwrap();
        assert_eq!((row.samples, row.median_ns, row.min_ns, row.max_ns), (4, 4.0, 1.0, 7.0));
    }
}
