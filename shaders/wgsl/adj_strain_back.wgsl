//! include: state, table, adjacency, adjoint
//! no table image
// adj_strain_back — per particle, the first half of a strain pass's adjoint
// (clothlab_cpu::adjoint::adj_strain_back), at the pass's input positions with the counts
// strain_count left in aux0: the gradient with respect to the pass's output point
// ȳ = x̄′ + v̄′/dt (planes 0, 1: the pass also moves the velocity by (y − x)/dt) taken back
// through the tethers to the point before them (into plane 2), each tether's share of its
// pin (planes 8, 9: the share, the pin's index in w; −1 none) and the strain limit's partial
// (plane 4, w).
@group(0) @binding(8) var<storage, read> tethers: array<Tether>;
@group(0) @binding(24) var<storage, read_write> strain_counts: array<vec4<f32>>;

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    var g = adjoint[adj_at(0u, i)].xyz + adjoint[adj_at(1u, i)].xyz * (1.0 / p.dt);
    let none = vec4<f32>(0.0, 0.0, 0.0, -1.0);
    adjoint[adj_at(8u, i)] = none;
    adjoint[adj_at(9u, i)] = none;
    let wi = pos[i].w;
    if wi == 0.0 {
        adjoint[adj_at(2u, i)] = vec4<f32>(g, 0.0);
        return;
    }
    let stretch = 1.0 + p.strain_limit;
    let aim = 1.0 + STRAIN_AIM * p.strain_limit;
    let xi = pos[i].xyz;
    let ci = strain_counts[i].x;
    // The point before the tethers: the pass's springs' corrections (limit_at's).
    var corr = vec3<f32>(0.0);
    var count = 0.0;
    if ci > 0.0 {
        let r = slot_row(i);
        for (var s = 0u; s < r.head; s++) {
            let slot = row_slot(i, r, s);
            if slot.neighbor < 0 {
                continue;
            }
            let b = u32(slot.neighbor);
            let d = pos[b].xyz - xi;
            let len = len3(d);
            if len > stretch * slot.rest {
                let wb = pos[b].w;
                corr += d * (wi * (len - aim * slot.rest) / ((wi + wb) * len * max(max(ci, strain_counts[b].x), 1.0)));
                count += 1.0;
            }
        }
    }
    var z = xi;
    if count > 0.0 {
        z = xi + corr;
    }
    // The tethers in order, each one's input kept; then back, last first.
    var before = array<vec3<f32>, TETHER_SLOTS>();
    var on = array<bool, TETHER_SLOTS>();
    for (var t = 0u; t < TETHER_SLOTS; t++) {
        let tether = tethers[i * TETHER_SLOTS + t];
        before[t] = z;
        on[t] = false;
        if tether.pin < 0 {
            continue;
        }
        let pin = pos[u32(tether.pin)].xyz;
        let d = z - pin;
        let len = len3(d);
        let max_len = stretch * tether.rest;
        if len > max_len {
            on[t] = true;
            z = pin + d * (max_len / len);
        }
    }
    var g_tau = 0.0;
    for (var k = TETHER_SLOTS; k > 0u; k--) {
        let t = k - 1u;
        if !on[t] {
            continue;
        }
        let tether = tethers[i * TETHER_SLOTS + t];
        let d = before[t] - pos[u32(tether.pin)].xyz;
        let len = len3(d);
        let n = d * (1.0 / len);
        let max_len = stretch * tether.rest;
        let through = (g - n * dot3(n, g)) * (max_len / len);
        adjoint[adj_at(8u + t, i)] = vec4<f32>(g - through, f32(tether.pin));
        g_tau += tether.rest * dot3(n, g);
        g = through;
    }
    adjoint[adj_at(2u, i)] = vec4<f32>(g, 0.0);
    adjoint[adj_at(4u, i)].w += g_tau;
}
