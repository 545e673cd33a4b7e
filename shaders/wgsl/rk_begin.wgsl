//! include: state, aux
//! worlds
// rk_begin — the start of a Runge–Kutta substep (core::cpu::integrators::rk_begin): saves
// x₀, the damped v₀ and the wind force, and writes v₀ to the velocities.
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let x4 = pos[world_base + i];
    let v0 = vec4<f32>(vel[world_base + i].xyz * (1.0 - p.damping), 0.0);
    aux0[world_base + i] = x4;
    aux1[world_base + i] = v0;
    aux4[world_base + i] = force[world_base + i];
    vel[world_base + i] = v0;
}
