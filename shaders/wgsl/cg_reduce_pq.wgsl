//! include: state, aux
//! worlds
// cg_reduce_pq — one workgroup folds the partials of p·q; α = r·z / p·q, 0 when p·q is
// not positive (core::cpu::integrators::cg_alpha).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(local_invocation_index) li: u32, @builtin(global_invocation_id) id: vec3<u32>) {
    p = step_params;
    let total = fold_partials(li);
    if li == 0u {
        var s = scalars[world_index];
        s.y = total;
        s.z = select(0.0, s.x / total, total > 0.0);
        scalars[world_index] = s;
    }
}
