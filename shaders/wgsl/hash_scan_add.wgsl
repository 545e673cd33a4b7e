//! include: state, hash, hash_fn
// hash_scan_add — per four consecutive buckets (one block's offset load for the four): each
// one's end in the whole array, its block's offset added
// (core::cpu::self_collide::hash_scan_add).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let first = 4u * flat_id(id, groups);
    let size = table_size();
    if first >= size {
        return;
    }
    // WORKGROUP is a multiple of 4: the four share a block.
    let offset = totals[4u * (first / WORKGROUP) + 2u];
    for (var b = first; b < min(first + 4u, size); b++) {
        cells[b] += offset;
    }
}
