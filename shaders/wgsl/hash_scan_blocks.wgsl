//! include: state, hash, hash_fn
// hash_scan_blocks — per WORKGROUP consecutive buckets (one invocation each, in order, no
// barriers: on lavapipe a workgroup-wide scan's twelve barriers cost more than the sums):
// the inclusive prefix of the counts in place, the block's total into totals[4g + 2]
// (core::cpu::self_collide::hash_scan_blocks).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let g = flat_id(id, groups);
    let size = table_size();
    let first = g * WORKGROUP;
    if first >= size {
        return;
    }
    let last = min(first + WORKGROUP, size);
    var acc = 0u;
    for (var b = first; b < last; b++) {
        acc += cells[b];
        cells[b] = acc;
    }
    totals[4u * g + 2u] = acc;
}
