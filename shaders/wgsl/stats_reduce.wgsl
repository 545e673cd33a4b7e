//! include: stats
// stats_reduce — one workgroup folds the partials of `stats` (one per workgroup of that
// dispatch) into the substep's entry: strided sums per invocation, then subgroups and
// workgroup memory as in `stats`. No atomics.
@group(0) @binding(17) var<storage, read_write> stats_max: array<f32>;
@group(0) @binding(18) var<storage, read_write> stats_energy: array<f32>;
@group(0) @binding(19) var<storage, read_write> partials: array<vec2<f32>>;

var<workgroup> by_subgroup: array<vec2<f32>, 64>;

@compute @workgroup_size(64)
fn main(
    @builtin(local_invocation_index) li: u32,
    @builtin(subgroup_id) sg: u32,
    @builtin(num_subgroups) num_sg: u32,
    @builtin(subgroup_invocation_id) lane: u32,
    @builtin(subgroup_size) sg_size: u32,
) {
    let count = (p.n * p.n + WORKGROUP - 1u) / WORKGROUP;
    var acc = vec2<f32>(0.0);
    for (var k = li; k < count; k += WORKGROUP) {
        acc = vec2<f32>(max(acc.x, partials[k].x), acc.y + partials[k].y);
    }
    let m = subgroupMax(acc.x);
    let e = subgroupAdd(acc.y);
    if lane == 0u {
        by_subgroup[sg] = vec2<f32>(m, e);
    }
    workgroupBarrier();
    if sg == 0u {
        var total = vec2<f32>(0.0);
        for (var k = lane; k < num_sg; k += sg_size) {
            total = vec2<f32>(max(total.x, by_subgroup[k].x), total.y + by_subgroup[k].y);
        }
        let wm = subgroupMax(total.x);
        let we = subgroupAdd(total.y);
        if lane == 0u {
            stats_max[stats_push.substep] = wm;
            stats_energy[stats_push.substep] = we;
        }
    }
}
