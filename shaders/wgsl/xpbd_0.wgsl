//! include: state, table, aux, xpbd, xpbd_grid, adjacency
//! worlds
// xpbd_0 — XPBD pass 0 of 12: the springs in slot 1 (offset (1, 0)) of the particles of
// colour 0 (core::cpu::integrators::XPBD_PASSES).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    xpbd_pass(i, 1u, 1, 0, 0u, 0u, 0u);
}
