//! include: state, aux
//! worlds
// vbd_finish — the end of a VBD substep (core::cpu::vbd::vbd_finish): x = x⁰ + D (x⁰ in
// aux1, D in aux2), v = v' + (D − h v')/h (v' in aux0), with pins, grab and floor as
// every integrator ends.
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let x4 = aux1[world_base + i];
    let d = aux2[world_base + i].xyz;
    let v = aux0[world_base + i].xyz;
    let m = finish_at(i, x4, x4.xyz + d, v + (d - v * p.dt) * (1.0 / p.dt));
    vel[world_base + i] = vec4<f32>(m.v, 0.0);
    pos[world_base + i] = vec4<f32>(m.x, x4.w);
}
