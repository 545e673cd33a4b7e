//! include: state, tri, tri_floats, cells
//! worlds
// tri_clamp_sum — per particle: a free vertex's displacement since the start, in
// TRI_MEAN_UNITs, into the 64-bit sums (two words, the carry added to the high one), and
// the count (core::cpu::tri_contact::tri_clamp_sum).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let x = pos[world_base + i];
    if x.w <= 0.0 {
        return;
    }
    let s = tri_floats[world_base + i];
    for (var c = 0u; c < 3u; c++) {
        let units = i32((x[c] - s[c]) / TRI_MEAN_UNIT);
        let lo = bitcast<u32>(units);
        let old = atomicAdd(&tri_ints[ib() + TRI_AT_MEAN + 2u * c], lo);
        let carry = select(0u, 1u, old + lo < old);
        atomicAdd(&tri_ints[ib() + TRI_AT_MEAN + 2u * c + 1u], select(0u, 0xffffffffu, units < 0i) + carry);
    }
    atomicAdd(&tri_ints[ib() + TRI_AT_FREE], 1u);
}
