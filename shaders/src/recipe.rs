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
    /// One per spring of the flat list.
    Springs,
    /// One per triangle.
    Triangles,
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
}

const fn d(kernel: &'static str, label: &'static str, count: Count) -> Dispatch {
    Dispatch { kernel, label, count, clear_normal: false, flips: false }
}

/// The dispatch that runs `kernel` alone (kernel tests, `clothlab validate`).
pub fn dispatch_for(kernel: &'static str) -> Dispatch {
    let base = kernel.trim_end_matches("_imm");
    let count = if base.starts_with("springs_scatter") {
        Count::Springs
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
    }
}

/// The `<kernel>_imm` twin that reads the step constants from immediates.
fn with_immediates(kernel: &'static str) -> &'static str {
    crate::kernel(&format!("{kernel}_imm")).map_or(kernel, |k| k.name)
}

/// What the adapter offers that the recipes use.
#[derive(Debug, Clone, Copy)]
pub struct Caps {
    /// `atomic<f32>` add in storage buffers.
    pub float_atomics: bool,
    /// Immediates (push constants) large enough for the step constants.
    pub immediates: bool,
}

/// The dispatches of one substep for `variant` with `strain_passes` strain passes; the
/// naive scatters use float atomics where the adapter has them, the optimized kernels
/// read the step constants from immediates where it has those.
pub fn recipe(variant: Variant, strain_passes: u32, caps: Caps) -> Vec<Dispatch> {
    let float_atomics = caps.float_atomics;
    let strain = Dispatch { flips: true, ..d("strain_limit", "strain_limit", Count::Particles) };
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
            r.push(d("forces_springs", FORCES_SPRINGS, Count::Particles));
            r.push(d("integrate_collide", INTEGRATE_COLLIDE, Count::Particles));
            r.extend((0..strain_passes).map(|_| strain));
            r.push(d("tri_normals", KernelId::TriNormals.name(), Count::Triangles));
            r.push(d("vertex_normals", KernelId::VertexNormals.name(), Count::Particles));
            if caps.immediates {
                for dsp in &mut r {
                    dsp.kernel = with_immediates(dsp.kernel);
                }
            }
        }
    }
    r
}

/// Workgroups of 64 for `count` invocations, as a 2-D grid (x ≤ 65535).
pub fn groups(count: u32) -> (u32, u32) {
    let g = count.div_ceil(64).max(1);
    let x = g.min(65535);
    (x, g.div_ceil(x))
}
