//! include: state, tri, cells
//! worlds
// tri_separate_share — per owner: its pairs' responses spread over their vertices, by the
// most pairs any of them is in, into the fixed-point sums (the separation's pushes;
// core::cpu::tri_contact::tri_share).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let o = flat_id(id, groups);
    if o >= num_owners() {
        return;
    }
    share_pass(o, false);
}
