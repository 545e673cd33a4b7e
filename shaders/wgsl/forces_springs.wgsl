//! include: state, table, gather
// forces + springs fused (optimized variant): one read and one write of the force.
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    force[i] = springs_at(i, forces_at(i, force[i]));
}
