//! Kernel ids and the per-kernel timing table every solver reports.

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};

/// The kernels of one substep, in the thesis's order. Names are shared by the CPU twins,
/// the WGSL files and the timing labels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum KernelId {
    /// Gravity and drag.
    Forces,
    /// Spring forces.
    Springs,
    /// Verlet step, pins, grab, floor.
    Integrate,
    /// Spheres and boxes.
    Collide,
    /// Provot strain limit (one label for all passes of a substep).
    StrainLimit,
    /// Face normals.
    TriNormals,
    /// Vertex normals and wind.
    VertexNormals,
}

impl KernelId {
    /// All kernels in step order.
    pub const ALL: [KernelId; 7] = [
        KernelId::Forces,
        KernelId::Springs,
        KernelId::Integrate,
        KernelId::Collide,
        KernelId::StrainLimit,
        KernelId::TriNormals,
        KernelId::VertexNormals,
    ];

    /// The kernel's name: file name, function name and timing label.
    pub fn name(self) -> &'static str {
        match self {
            KernelId::Forces => "forces",
            KernelId::Springs => "springs",
            KernelId::Integrate => "integrate",
            KernelId::Collide => "collide",
            KernelId::StrainLimit => "strain_limit",
            KernelId::TriNormals => "tri_normals",
            KernelId::VertexNormals => "vertex_normals",
        }
    }
}

/// Label of the CPU solvers' fused `forces` + `springs` sweep.
pub const FORCES_SPRINGS: &str = "forces+springs";
/// Label of the CPU solvers' fused `integrate` + `collide` sweep.
pub const INTEGRATE_COLLIDE: &str = "integrate+collide";
/// Label of the whole-substep row.
pub const SUBSTEP: &str = "substep";
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
            .filter(|(_, q)| !q.is_empty())
            .map(|(label, q)| {
                let mut v: Vec<f64> = q.iter().copied().collect();
                v.sort_by(f64::total_cmp);
                let mid = v.len() / 2;
                let median = if v.len() % 2 == 1 { v[mid] } else { 0.5 * (v[mid - 1] + v[mid]) };
                TimingRow {
                    label: label.clone(),
                    samples: v.len(),
                    median_ns: median,
                    min_ns: v[0],
                    max_ns: v[v.len() - 1],
                }
            })
            .collect();
        KernelTimings { rows }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
