//! include: table, stats, particle_stats
// stats — per particle, reduced without atomics: a subgroup reduction (subgroupMax,
// subgroupAdd), then the workgroup's subgroups through workgroup memory; one partial per
// workgroup, which stats_reduce folds into the substep's entry.
@group(0) @binding(19) var<storage, read_write> partials: array<vec2<f32>>;

var<workgroup> by_subgroup: array<vec2<f32>, 64>;

@compute @workgroup_size(64)
fn main(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(subgroup_id) sg: u32,
    @builtin(num_subgroups) num_sg: u32,
    @builtin(subgroup_invocation_id) lane: u32,
    @builtin(subgroup_size) sg_size: u32,
) {
    let i = flat_id(id, groups);
    // No early return: every invocation takes part in the reductions.
    var v = vec2<f32>(0.0);
    if i < p.n * p.n {
        v = particle_stats(i);
    }
    let m = subgroupMax(v.x);
    let e = subgroupAdd(v.y);
    if lane == 0u {
        by_subgroup[sg] = vec2<f32>(m, e);
    }
    workgroupBarrier();
    if sg == 0u {
        var acc = vec2<f32>(0.0);
        for (var k = lane; k < num_sg; k += sg_size) {
            acc = vec2<f32>(max(acc.x, by_subgroup[k].x), acc.y + by_subgroup[k].y);
        }
        let wm = subgroupMax(acc.x);
        let we = subgroupAdd(acc.y);
        if lane == 0u {
            partials[wg.x + wg.y * groups.x] = vec2<f32>(wm, we);
        }
    }
}
