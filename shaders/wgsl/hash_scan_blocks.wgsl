//! include: state, hash_vec4, hash_fn, cells
//! worlds
// hash_scan_blocks — per WORKGROUP consecutive buckets (one invocation each, in order, no
// barriers: on lavapipe a workgroup-wide scan's twelve barriers cost more than the sums),
// read and written four at a time: the inclusive prefix of the counts in place, from the
// block's offset (totals[4g + 2] after hash_scan_top): each bucket's end in the whole
// array (core::cpu::self_collide::hash_scan_blocks).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let g = flat_id(id, groups);
    let size = table_size();
    let first = g * WORKGROUP;
    if first >= size {
        return;
    }
    // The table's size is a multiple of 4.
    let last = min(first + WORKGROUP, size);
    // (A batch's world: its own table and blocks, whole blocks from table_base.)
    var acc = totals[4u * (block_base() + g) + 2u];
    let q0 = table_base() / 4u;
    for (var q = q0 + first / 4u; q < q0 + last / 4u; q++) {
        var v = cells4[q];
        v.x += acc;
        v.y += v.x;
        v.z += v.y;
        v.w += v.z;
        cells4[q] = v;
        acc = v.w;
    }
}
