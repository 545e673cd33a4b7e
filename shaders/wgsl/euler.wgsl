//! include: state
// euler — explicit Euler per particle (core::cpu::integrators::euler): x' = x + u,
// u' = u + f dt²/m with u = (1 − damping)(x − prev); pins, grab, floor.
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let x4 = pos[i];
    let u0 = (x4.xyz - prev[i].xyz) * (1.0 - p.damping);
    let u1 = u0 + accel_dt2(force[i].xyz);
    let m = finish_at(i, x4, x4.xyz + u0, u1);
    prev[i] = vec4<f32>(m.xp, 0.0);
    pos[i] = vec4<f32>(m.x, x4.w);
}
