//! include: state, aux
//! worlds
// vbd_begin — Vertex Block Descent's prediction (core::cpu::vbd::vbd_begin): D = h v' with
// v' = (1 − damping) v + f h/m (the force buffer after `forces`); a pinned particle
// D = 0, the grabbed one D = target − x. aux0 = v' (0 where held), aux1 = x⁰, aux2 = D;
// the positions stay x⁰ until vbd_finish.
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let x4 = pos[world_base + i];
    var d = vec3<f32>(0.0);
    var v = vec3<f32>(0.0);
    if i32(i) == p.grab_index {
        d = p.grab_target.xyz - x4.xyz;
    } else if x4.w != 0.0 {
        v = vel[world_base + i].xyz * (1.0 - p.damping) + force[world_base + i].xyz * dt_over_mass(x4.w);
        d = v * p.dt;
    }
    aux0[world_base + i] = vec4<f32>(v, 0.0);
    aux1[world_base + i] = x4;
    aux2[world_base + i] = vec4<f32>(d, 0.0);
}
