//! include: state, hash_atomic, hash_fn
// hash_count — per particle: one more in its bucket's count (core::cpu::self_collide::
// hash_count; the recipe clears the counts before).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    atomicAdd(&cells[bucket(cell_of(pos[i].xyz), table_size())], 1u);
}
