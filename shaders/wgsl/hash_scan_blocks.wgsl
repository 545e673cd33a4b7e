//! include: state, hash, hash_fn
// hash_scan_blocks — per bucket: the exclusive prefix of the counts within its workgroup
// into cells[b].y, the workgroup's total into cells[g].w (core::cpu::self_collide).
@compute @workgroup_size(WORKGROUP)
fn main(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    p = step_params;
    let b = flat_id(id, groups);
    let size = table_size();
    var c = 0u;
    if b < size {
        c = cells[4u * b];
    }
    let incl = workgroup_scan(c, li);
    if b < size {
        cells[4u * b + 1u] = incl - c;
    }
    let g = wg.x + wg.y * groups.x;
    if li == WORKGROUP - 1u && g * WORKGROUP < size {
        cells[4u * g + 3u] = incl;
    }
}
