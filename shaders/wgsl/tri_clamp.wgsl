//! include: state, tri, tri_floats, cells
//! worlds
// tri_clamp — per particle, where some vertex is over its bound from the mean: its motion
// since the start cut to its bound, the cut taken from its velocity
// (core::cpu::tri_contact::tri_clamp).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() || load_int(TRI_AT_OVER) == 0u {
        return;
    }
    let s = tri_floats[world_base + i];
    let x = pos[world_base + i];
    let d = x.xyz - s.xyz;
    let len = len3(d);
    if len <= s.w || !(len <= 3.40282347e38) {
        return;
    }
    let to = s.xyz + d * (s.w * (1.0 / len));
    let v = vel[world_base + i];
    vel[world_base + i] = vec4<f32>(v.xyz + (to - x.xyz) * (1.0 / p.dt), v.w);
    pos[world_base + i] = vec4<f32>(to, x.w);
    atomicAdd(&tri_ints[ib() + TRI_AT_CLAMPED], 1u);
}
