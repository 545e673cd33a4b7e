//! include: state
//! worlds
// euler — explicit Euler per particle (core::cpu::integrators::euler): x' = x + v dt,
// v' = v + f dt/m with v damped by (1 − damping) first; pins, grab, floor.
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let x4 = pos[world_base + i];
    let v0 = vel[world_base + i].xyz * (1.0 - p.damping);
    let v1 = v0 + accel_dt(force[world_base + i].xyz, x4.w);
    let m = finish_at(i, x4, x4.xyz + v0 * p.dt, v1);
    vel[world_base + i] = vec4<f32>(m.v, 0.0);
    pos[world_base + i] = vec4<f32>(m.x, x4.w);
}
