//! include: state, aux, rk
//! worlds
// rk2_1 — the midpoint method's first stage: to the midpoint (core::cpu::integrators::RK2).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    rk_stage(i, 0.5, 0.0, true, false);
}
