//! include: state, aux
//! worlds
// cg_step — Δv += α p, r −= α q (core::cpu::integrators::cg_step); the partial sums of
// the new r·z.
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
        let alpha = scalars[world_index].z;
        let x = aux0[world_base + i].xyz + aux2[world_base + i].xyz * alpha;
        let r4 = vec4<f32>(aux1[world_base + i].xyz - aux3[world_base + i].xyz * alpha, aux1[world_base + i].w);
        aux0[world_base + i] = vec4<f32>(x, 0.0);
        aux1[world_base + i] = r4;
        term = dot3(r4.xyz, precondition(r4));
    }
    store_partial(workgroup_sum(term, li), li, wg, groups);
}
