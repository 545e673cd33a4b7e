//! include: state, tri, tri_floats, cells
//! worlds
// tri_start — per particle: its start position and its bound at the reach's fraction;
// the reach and the grids' cell into the scalars (core::cpu::tri_contact::tri_start).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let fastest = load_f(TRI_AT_SPEED);
    let g = len3(p.gravity.xyz);
    let motion = fastest * p.dt + g * (p.dt * p.dt);
    let t = p.self_thickness;
    // The cap t + 2 s as s + s (exact) added to t: Mesa fuses t + 2.0 * s into one
    // rounding, core rounds twice (TRI_MAX_REACH_SPACINGS is 2: layout.rs checks).
    let reach = clamp(TRI_REACH_PER_MOTION * motion, t, t + (p.spacing + p.spacing));
    tri_floats[world_base + i] = vec4<f32>(pos[world_base + i].xyz, TRI_BOUND_FRACTION * reach);
    if i == 0u {
        atomicStore(&tri_ints[ib() + TRI_AT_REACH], bitcast<u32>(reach));
        atomicStore(&tri_ints[ib() + TRI_AT_CELL], bitcast<u32>(max(2.0 * reach, 1.5 * p.spacing)));
    }
}
