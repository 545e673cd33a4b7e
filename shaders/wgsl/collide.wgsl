//! include: state, colliders
//! worlds
// collide — per particle: push out of every collider (the floor, spheres, boxes, capsules,
// bodies' fields; shared/colliders.wgsl).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let x4 = pos[world_base + i];
    if !is_free(i, x4.w) {
        return;
    }
    let m = collided(Moved(x4.xyz, vel[world_base + i].xyz));
    pos[world_base + i] = vec4<f32>(m.x, x4.w);
    vel[world_base + i] = vec4<f32>(m.v, 0.0);
}
