//! include: state, table, aux, cg, adjacency
//! worlds
// cg_matvec — q = S A p, zero for held particles (core::cpu::integrators::cg_matvec); the
// partial sums of p·q.
@compute @workgroup_size(WORKGROUP)
fn main(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    p = step_params;
    let i = flat_id(id, groups);
    // No early return: every invocation takes part in the workgroup sum.
    var term = 0.0;
    if i < num_particles() {
        var q = vec3<f32>(0.0);
        if !held(i, pos[world_base + i].w) {
            q = apply_at(i, true).v;
        }
        aux3[world_base + i] = vec4<f32>(q, 0.0);
        term = dot3(aux2[world_base + i].xyz, q);
    }
    store_partial(workgroup_sum(term, li), li, wg, groups);
}
