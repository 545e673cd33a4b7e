//! include: wind, wind_fn, adjacency
//! worlds
// vertex_normals — per particle (naive variant): normalise the sum tri_normals_scatter
// accumulated with atomics, and the wind force into the force buffer.
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= p.num_particles {
        return;
    }
    normal[world_base + i] = vec4<f32>(normalize_or_zero(normal[world_base + i].xyz), 0.0);
    force[world_base + i] = vec4<f32>(wind_at(i), 0.0);
}
