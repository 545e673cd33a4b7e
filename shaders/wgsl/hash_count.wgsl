//! include: state, hash_atomic, hash_totals_atomic, hash_fn, cells
//! worlds
// hash_count — per particle: one more in its bucket's count and in its block's total
// (core::cpu::self_collide::hash_count; the recipe clears both before). The blocks'
// totals here spare the scan a pass that adds their offsets back (a dispatch costs
// lavapipe about 50 µs; the second atomic, into a few KiB that stay cached, about none).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    count_point(pos[world_base + i].xyz);
}
