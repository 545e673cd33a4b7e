//! include: state, aux
// rk_begin — the start of a Runge–Kutta substep (core::cpu::integrators::rk_begin): saves
// x₀, the damped v₀ and the wind force, and writes v₀ to the velocities.
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let x4 = pos[i];
    let v0 = vec4<f32>(vel[i].xyz * (1.0 - p.damping), 0.0);
    aux0[i] = x4;
    aux1[i] = v0;
    aux4[i] = force[i];
    vel[i] = v0;
}
