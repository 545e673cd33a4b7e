//! include: state, aux
//! worlds
// implicit_finish — v₁ = (1 − damping) v₀ + Δv, x₁ = x₀ + v₁ dt, with pins, grab and floor
// (core::cpu::integrators::implicit_finish).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let x4 = pos[world_base + i];
    let v1 = vel[world_base + i].xyz * (1.0 - p.damping) + aux0[world_base + i].xyz;
    let m = finish_at(i, x4, x4.xyz + v1 * p.dt, v1);
    vel[world_base + i] = vec4<f32>(m.v, 0.0);
    pos[world_base + i] = vec4<f32>(m.x, x4.w);
}
