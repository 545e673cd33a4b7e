//! include: state, table, adjacency, adjoint
//! no table image
// adj_strain_gather — per particle, the second half of a strain pass's adjoint
// (clothlab_cpu::adjoint::adj_strain_gather), after adj_strain_back: the gradient with
// respect to the pass's input position is −v̄′/dt plus the point's own (plane 2) taken
// through this particle's over-stretched springs' corrections and its neighbours' onto it
// (a gather: each spring's k (ḡ − (A/len)(ḡ − n n·ḡ)) from either end), and, on a pinned
// particle, every tether's share of it (planes 8, 9 of every particle: the pins are few);
// the strain limit's partial of its own springs (plane 4, w). The velocity's gradient
// stays (v′ = v + (y − x)/dt).
@group(0) @binding(24) var<storage, read_write> strain_counts: array<vec4<f32>>;

// The correction's adjoint of the spring from a (mobility wa, count ca, its point's
// gradient ga) to b: d = x_b − x_a.
fn spring_back(ga: vec3<f32>, d: vec3<f32>, len: f32, rest: f32, wa: f32, wb: f32, ca: f32, cb: f32) -> vec3<f32> {
    let aim = 1.0 + STRAIN_AIM * p.strain_limit;
    let k = wa / ((wa + wb) * max(max(ca, cb), 1.0));
    let n = d * (1.0 / len);
    return k * (ga - (aim * rest / len) * (ga - n * dot3(n, ga)));
}

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    let np = num_particles();
    if i >= np {
        return;
    }
    let stretch = 1.0 + p.strain_limit;
    let xi = pos[i].xyz;
    let wi = pos[i].w;
    let ci = strain_counts[i].x;
    let gi = adjoint[adj_at(2u, i)].xyz;
    var gx = gi;
    var g_tau = 0.0;
    let r = slot_row(i);
    for (var s = 0u; s < r.head; s++) {
        let slot = row_slot(i, r, s);
        if slot.neighbor < 0 {
            continue;
        }
        let b = u32(slot.neighbor);
        let d = pos[b].xyz - xi;
        let len = len3(d);
        if !(len > stretch * slot.rest) {
            continue;
        }
        let wb = pos[b].w;
        let cb = strain_counts[b].x;
        if wi != 0.0 {
            let md = spring_back(gi, d, len, slot.rest, wi, wb, ci, cb);
            gx -= md;
            let k = wi / ((wi + wb) * max(max(ci, cb), 1.0));
            g_tau -= k * dot3(d * (1.0 / len), gi) * slot.rest * STRAIN_AIM;
        }
        if wb != 0.0 {
            gx += spring_back(adjoint[adj_at(2u, b)].xyz, -d, len, slot.rest, wb, wi, cb, ci);
        }
    }
    if wi == 0.0 {
        let me = f32(i);
        for (var k = 0u; k < np; k++) {
            for (var t = 8u; t < 10u; t++) {
                let share = adjoint[adj_at(t, k)];
                if share.w == me {
                    gx += share.xyz;
                }
            }
        }
    }
    adjoint[adj_at(0u, i)] = vec4<f32>(gx - adjoint[adj_at(1u, i)].xyz * (1.0 / p.dt), 0.0);
    adjoint[adj_at(4u, i)].w += g_tau;
}
