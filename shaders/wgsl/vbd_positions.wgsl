//! include: state, aux
//! worlds
// vbd_positions — the positions at VBD's iterate x⁰ + D (core::cpu::vbd::vbd_positions),
// after the prediction and each Chebyshev step where the contact between triangles' terms
// are found at them (tri_vbd).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let x4 = aux1[world_base + i];
    pos[world_base + i] = vec4<f32>(x4.xyz + aux2[world_base + i].xyz, x4.w);
}
