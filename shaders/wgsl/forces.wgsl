//! include: state
//! worlds
// forces — per particle: gravity and drag added to the wind force in the force buffer.
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let k = world_base + i;
    force[k] = forces_at(force[k], vel[k].xyz, pos[k].w);
}
