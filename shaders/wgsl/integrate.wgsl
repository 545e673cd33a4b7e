//! include: state
//! worlds
// integrate — per particle: Verlet in velocity form, pins, grab, floor.
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let x4 = pos[world_base + i];
    let m = integrated(i, x4, vel[world_base + i].xyz);
    vel[world_base + i] = vec4<f32>(m.v, 0.0);
    pos[world_base + i] = vec4<f32>(m.x, x4.w);
}
