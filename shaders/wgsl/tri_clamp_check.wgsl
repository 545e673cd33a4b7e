//! include: state, tri, tri_floats, cells
//! worlds
// tri_clamp_check — per particle: whether it is farther than its bound from the free
// vertices' mean displacement, and whether it moved farther than its bound
// (core::cpu::tri_contact::tri_clamp_check).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let count = 1.0 / f32(max(load_int(TRI_AT_FREE), 1u));
    var mean = vec3<f32>(0.0);
    for (var c = 0u; c < 3u; c++) {
        let lo = load_int(TRI_AT_MEAN + 2u * c);
        let hi = load_int(TRI_AT_MEAN + 2u * c + 1u);
        mean[c] = (f32(bitcast<i32>(hi)) * 4294967296.0 + f32(lo)) * TRI_MEAN_UNIT * count;
    }
    let s = tri_floats[world_base + i];
    let d = pos[world_base + i].xyz - s.xyz;
    if !(len3(d - mean) <= s.w) {
        atomicStore(&tri_ints[ib() + TRI_AT_OVER], 1u);
    }
    if len3(d) > s.w {
        atomicStore(&tri_ints[ib() + TRI_AT_MOVED], 1u);
    }
}
