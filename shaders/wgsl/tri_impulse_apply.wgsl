//! include: state, tri, cells
//! worlds
// tri_impulse_apply — per particle: its sums added (the velocity pass's impulses) and cleared
// (core::cpu::tri_contact::tri_apply).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let v = vel[world_base + i];
    vel[world_base + i] = vec4<f32>(v.xyz + take_sums(i, true), v.w);
}
