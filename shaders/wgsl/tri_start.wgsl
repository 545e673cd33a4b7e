//! include: state, tri, tri_floats, cells
// tri_start — per particle: its start position, its reach (from its own speed) and its
// bound at its reach's fraction; the largest reach (the fastest's) and the grids' cell
// into the scalars (core::cpu::tri_contact::tri_start).
// core::tri_contact::reach_at_speed.
fn reach_at_speed(speed: f32) -> f32 {
    let g = len3(p.gravity.xyz);
    let motion = speed * p.dt + g * (p.dt * p.dt);
    let t = p.self_thickness;
    // The cap t + 2 s as s + s (exact) added to t: Mesa fuses t + 2.0 * s into one
    // rounding, core rounds twice (TRI_MAX_REACH_SPACINGS is 2: layout.rs checks).
    return clamp(TRI_REACH_PER_MOTION * motion, t, t + (p.spacing + p.spacing));
}

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let reach = reach_at_speed(load_f(TRI_AT_SPEED));
    // core::tri_contact::speed_of: a free vertex's finite speed, else 0.
    let s = len3(vel[i].xyz);
    let own = reach_at_speed(select(0.0, s, pos[i].w > 0.0 && s <= 3.40282347e38));
    tri_floats[i] = vec4<f32>(pos[i].xyz, TRI_BOUND_FRACTION * own);
    atomicStore(&tri_ints[reaches_at() + i], bitcast<u32>(own));
    if i == 0u {
        atomicStore(&tri_ints[TRI_AT_REACH], bitcast<u32>(reach));
        atomicStore(&tri_ints[TRI_AT_CELL], bitcast<u32>(max(2.0 * reach, 1.5 * p.spacing)));
    }
}
