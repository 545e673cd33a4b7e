//! include: state, colliders
// collide — per particle: push out of spheres and boxes.
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    collide_at(i);
}
