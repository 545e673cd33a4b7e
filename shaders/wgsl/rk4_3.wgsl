//! include: state, aux, rk
//! worlds
// rk4_3 — RK4's third stage (core::cpu::integrators::RK4).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    rk_stage(i, 1.0, 1.0 / 3.0, false, false);
}
