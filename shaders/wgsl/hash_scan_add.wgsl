//! include: state, hash, hash_fn
// hash_scan_add — per bucket: its end in the whole array (its block's offset added)
// (core::cpu::self_collide::hash_scan_add).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let b = flat_id(id, groups);
    if b >= table_size() {
        return;
    }
    cells[b] += sorted[4u * (b / WORKGROUP) + 2u];
}
