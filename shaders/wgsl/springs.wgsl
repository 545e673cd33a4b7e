//! include: state, table, gather, adjacency
//! worlds
// springs — per particle: gather the 12 slots of the spring table.
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    interior = interior_slots;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    force[world_base + i] = vec4<f32>(table_springs(i, point(i), force[world_base + i].xyz), 0.0);
}
