//! include: table, stats, particle_stats, adjacency
// stats — per particle, reduced without atomics: a subgroup reduction (subgroupMax,
// subgroupAdd), then the workgroup's subgroups through workgroup memory; one partial per
// workgroup, which stats_reduce folds into the substep's entry.
@group(0) @binding(19) var<storage, read_write> partials: array<vec2<f32>>;


@compute @workgroup_size(WORKGROUP)
fn main(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(subgroup_id) sg: u32,
    @builtin(num_subgroups) num_sg: u32,
    @builtin(subgroup_invocation_id) lane: u32,
    @builtin(subgroup_size) sg_size: u32,
) {
    p = step_params;
    let i = flat_id(id, groups);
    // No early return: every invocation takes part in the reductions.
    var v = vec2<f32>(0.0);
    if i < p.num_particles {
        v = particle_stats(i);
    }
    let total = fold_workgroup(v, sg, num_sg, lane, sg_size);
    if sg == 0u && lane == 0u {
        partials[wg.x + wg.y * groups.x] = total;
    }
}
