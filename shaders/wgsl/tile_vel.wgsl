//! include: state, aux
// tile_vel — the tiled substep's new velocities (aux0, substep_tile.wgsl) into place, after
// the swap: substep_tile cannot write them over the velocities other workgroups still read
// in their halos.
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    vel[i] = aux0[i];
}
