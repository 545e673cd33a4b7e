//! include: state, colliders
//! worlds
// integrate + collide fused (optimized variant): both touch only their own particle, which
// is loaded once and stored once.
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let x4 = pos[world_base + i];
    var m = integrated(i, x4, vel[world_base + i].xyz);
    if is_free(i, x4.w) {
        m = collided(m);
    }
    vel[world_base + i] = vec4<f32>(m.v, 0.0);
    pos[world_base + i] = vec4<f32>(m.x, x4.w);
}
