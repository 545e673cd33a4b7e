//! include: state, aux
//! worlds
// cg_reduce_rz — one workgroup folds the partials of r·z; β = new / old, 0 when the old
// one was not positive; the new one kept (core::cpu::integrators::cg_beta).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(local_invocation_index) li: u32, @builtin(global_invocation_id) id: vec3<u32>) {
    p = step_params;
    let total = fold_partials(li);
    if li == 0u {
        var s = scalars[world_index];
        s.w = select(0.0, total / s.x, s.x > 0.0);
        s.x = total;
        scalars[world_index] = s;
    }
}
