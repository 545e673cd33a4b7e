//! include: stats
// stats_reduce — one workgroup folds the partials of `stats` (one per workgroup of that
// dispatch) into the substep's entry: strided sums per invocation, then subgroups and
// workgroup memory as in `stats`. No atomics.
@group(0) @binding(17) var<storage, read_write> stats_max: array<f32>;
@group(0) @binding(18) var<storage, read_write> stats_energy: array<f32>;
@group(0) @binding(19) var<storage, read_write> partials: array<vec2<f32>>;


@compute @workgroup_size(WORKGROUP)
fn main(
    @builtin(local_invocation_index) li: u32,
    @builtin(subgroup_id) sg: u32,
    @builtin(num_subgroups) num_sg: u32,
    @builtin(subgroup_invocation_id) lane: u32,
    @builtin(subgroup_size) sg_size: u32,
) {
    p = step_params;
    let count = (p.num_particles + WORKGROUP - 1u) / WORKGROUP;
    var acc = vec2<f32>(0.0);
    for (var k = li; k < count; k += WORKGROUP) {
        acc = vec2<f32>(max(acc.x, partials[k].x), acc.y + partials[k].y);
    }
    let total = fold_workgroup(acc, sg, num_sg, lane, sg_size);
    if sg == 0u && lane == 0u {
        stats_max[stats_push.substep] = total.x;
        stats_energy[stats_push.substep] = total.y;
    }
}
