//! include: state, hash, hash_fn
// hash_scan_blocks — per WORKGROUP consecutive buckets (one invocation each, in order, no
// barriers: on lavapipe a workgroup-wide scan's twelve barriers cost more than the sums):
// the exclusive prefix of the counts into cells[b].y, the total into cells[g].w
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
        let c = cells[4u * b];
        cells[4u * b + 1u] = acc;
        acc += c;
    }
    cells[4u * g + 3u] = acc;
}
