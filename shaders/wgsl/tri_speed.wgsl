//! include: state, tri, cells
//! worlds
// tri_speed — per particle: the fastest free vertex's speed into the contact's scalars
// (core::cpu::tri_contact::tri_speed; the recipe clears the integers before).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let s = len3(vel[world_base + i].xyz);
    if pos[world_base + i].w > 0.0 && s <= 3.40282347e38 {
        atomicMax(&tri_ints[ib() + TRI_AT_SPEED], bitcast<u32>(s));
    }
}
