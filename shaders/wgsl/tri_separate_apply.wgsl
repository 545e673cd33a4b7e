//! include: state, tri, cells
//! worlds
// tri_separate_apply — per particle: its sums added (the separation's pushes) and cleared
// (core::cpu::tri_contact::tri_apply).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let d = take_sums(i, false);
    let x = pos[world_base + i];
    let v = vel[world_base + i];
    pos[world_base + i] = vec4<f32>(x.xyz + d, x.w);
    vel[world_base + i] = vec4<f32>(v.xyz + d * (1.0 / p.dt), v.w);
}
