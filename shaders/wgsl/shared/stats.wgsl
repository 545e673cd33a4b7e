// Per-substep statistics of the state (core::cpu::stats): the largest structural strain
// |L| / rest - 1 (each structural spring once, from its left or lower end: slots 1 and 3)
// and the kinetic energy 1/2 m |v|². The substep's index comes in immediates
// (push constants), so every substep of a frame writes its own entry.

@group(0) @binding(0) var<uniform> step_params: StepParams;
// Copied from step_params by the kernel's first statement (see shared/state.wgsl).
var<private> p: StepParams;
@group(0) @binding(1) var<storage, read_write> pos: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> vel: array<vec4<f32>>;

struct StatsPush {
    substep: u32,
}
var<immediate> stats_push: StatsPush;

var<workgroup> by_subgroup: array<vec2<f32>, 64>;

// (max, sum) of `v` over the workgroup without atomics: a subgroup reduction, then the
// subgroups' results through workgroup memory, folded by subgroup 0. Every invocation
// must call it; the result is valid in invocation 0 of subgroup 0 (`is_first`).
fn fold_workgroup(v: vec2<f32>, sg: u32, num_sg: u32, lane: u32, sg_size: u32) -> vec2<f32> {
    let m = subgroupMax(v.x);
    let e = subgroupAdd(v.y);
    if lane == 0u {
        by_subgroup[sg] = vec2<f32>(m, e);
    }
    workgroupBarrier();
    var total = vec2<f32>(0.0);
    if sg == 0u {
        var acc = vec2<f32>(0.0);
        for (var k = lane; k < num_sg; k += sg_size) {
            acc = vec2<f32>(max(acc.x, by_subgroup[k].x), acc.y + by_subgroup[k].y);
        }
        total = vec2<f32>(subgroupMax(acc.x), subgroupAdd(acc.y));
    }
    return total;
}
