//! include: state, tri, cells
//! worlds
// tri_impulse_count — per owner: one more in the count of every vertex one of its pairs'
// responses moves (the velocity pass's impulses; core::cpu::tri_contact::tri_count).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let o = flat_id(id, groups);
    if o >= num_owners() {
        return;
    }
    count_pass(o, true);
}
