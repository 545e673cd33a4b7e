//! include: state, hash, hash_fn
// hash_scan_add — per bucket: its start (its workgroup's offset added) into cells[b].y and
// the scatter's cursor cells[b].z (core::cpu::self_collide::hash_scan_add).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let b = flat_id(id, groups);
    if b >= table_size() {
        return;
    }
    let start = cells[4u * b + 1u] + cells[4u * (b / WORKGROUP) + 3u];
    cells[4u * b + 1u] = start;
    cells[4u * b + 2u] = start;
}
