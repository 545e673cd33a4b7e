//! include: state, hash_atomic, hash_fn
// hash_count — per particle: its bucket into sorted[4i], one more in its bucket's count
// (core::cpu::self_collide::hash_count; the recipe clears the counts before).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let b = bucket(cell_of(pos[i].xyz), table_size());
    sorted[4u * i] = b;
    atomicAdd(&cells[b], 1u);
}
