//! include: state, table, aux, cg, adjacency
//! worlds
// cg_begin — implicit Euler's solve starts (core::cpu::integrators::cg_begin): Δv = 0,
// r = dt f − dt² K v (w: the diagonal of A), p = z = r/diag; the partial sums of r·z.
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
        let x4 = pos[world_base + i];
        let a = apply_at(i, false);
        var r = vec3<f32>(0.0);
        if !held(i, x4.w) {
            r = force[world_base + i].xyz * p.dt - a.v;
        }
        let r4 = vec4<f32>(r, a.diag);
        let z = precondition(r4);
        aux0[world_base + i] = vec4<f32>(0.0);
        aux1[world_base + i] = r4;
        aux2[world_base + i] = vec4<f32>(z, 0.0);
        term = dot3(r, z);
    }
    store_partial(workgroup_sum(term, li), li, wg, groups);
}
