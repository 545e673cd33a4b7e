//! include: state, hash_vec4, hash_fn
// hash_scan_add — per four consecutive buckets (one read and one write of the four, one
// block-offset load): each one's end in the whole array, its block's offset added
// (core::cpu::self_collide::hash_scan_add).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let q = flat_id(id, groups);
    // The table's size is a multiple of 4, WORKGROUP too: the four share a block.
    if 4u * q >= table_size() {
        return;
    }
    cells4[q] += vec4<u32>(totals[4u * (4u * q / WORKGROUP) + 2u]);
}
