//! include: state, aux
//! worlds
// cg_direction — p = z + β p (core::cpu::integrators::cg_direction).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    aux2[world_base + i] = vec4<f32>(precondition(aux1[world_base + i]) + aux2[world_base + i].xyz * scalars[world_index].w, 0.0);
}
