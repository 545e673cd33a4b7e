//! include: state, colliders
//! worlds
// forces + integrate + collide fused: the thesis's optimized CUDA kernel ("Verlet"). The
// springs were added into the force buffer by a kernel before (scattered with atomics in
// the thesis, or gathered); gravity and drag are added here and the total force goes
// straight into the integration without being stored (one global-memory round trip less,
// as the thesis puts it), and the new position is pushed out of the colliders before it is
// written.
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let x4 = pos[world_base + i];
    let v = vel[world_base + i].xyz;
    let f = forces_at(force[world_base + i], v, x4.w).xyz;
    var m = integrated_with(i, x4, v, f);
    if is_free(i, x4.w) {
        m = collided(m);
    }
    vel[world_base + i] = vec4<f32>(m.v, 0.0);
    pos[world_base + i] = vec4<f32>(m.x, x4.w);
}
