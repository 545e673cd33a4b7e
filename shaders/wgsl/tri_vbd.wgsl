//! include: state, tri, range, cells
//! worlds
// tri_vbd — per owner: the contact terms of its pairs at the positions (VBD's iterate) for
// the vertices of one colour (the range's `first`; core::cpu::tri_contact::tri_vbd), added
// into their fixed-point sums, which vbd_colour_tri takes and clears.
@group(0) @binding(31) var<storage, read> colours: array<u32>;

// Whether vertex k's terms are gathered: in the colour, not held.
fn wanted(k: u32) -> bool {
    return colours[num_particles() + k] == pass_range.first && !held(k, pos[world_base + k].w);
}

fn add_word(k: u32, v: f32) {
    atomicAdd(&tri_ints[ib() + k], bitcast<u32>(i32(v)));
}

// The pair's energy ½ k (t − d)² as a side's force and block k w n nᵀ
// (core::tri_contact::vbd_terms), over k.
fn add_terms(ks: vec3<u32>, ws: vec3<f32>, sign: f32, n: vec3<f32>, scale: f32) {
    let at = vbd_terms_at();
    for (var i = 0u; i < 3u; i++) {
        let w = ws[i];
        if w == 0.0 || !wanted(ks[i]) {
            continue;
        }
        let f = n * (sign * w * scale);
        let hw = w * CONTACT_UNITS;
        let base = at + VBD_TERMS * ks[i];
        add_word(base, f.x);
        add_word(base + 1u, f.y);
        add_word(base + 2u, f.z);
        add_word(base + 3u, n.x * n.x * hw);
        add_word(base + 4u, n.y * n.y * hw);
        add_word(base + 5u, n.z * n.z * hw);
        add_word(base + 6u, n.x * n.y * hw);
        add_word(base + 7u, n.x * n.z * hw);
        add_word(base + 8u, n.y * n.z * hw);
    }
}

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let o = flat_id(id, groups);
    if o >= num_owners() {
        return;
    }
    let t = p.self_thickness;
    if !(t > 0.0) {
        return;
    }
    let np = num_particles();
    for (var k = 0u; k < kept(o); k++) {
        let other = tri_pairs[pb() + o * TRI_SLOTS + k];
        // The closest points only for a pair with a vertex to act on.
        var any = false;
        if o < np {
            let tri = tri_at(other);
            any = wanted(o) || wanted(tri.x) || wanted(tri.y) || wanted(tri.z);
        } else {
            let e = edge_at(o - np);
            let g = edge_at(other);
            any = wanted(e.x) || wanted(e.y) || wanted(g.x) || wanted(g.y);
        }
        if !any {
            continue;
        }
        let s = sides(o, other);
        let g = gap(s);
        let d = g.d;
        let n = g.n;
        if !(d < t) || !finite3(n) {
            continue;
        }
        let scale = (t - d) * (1.0 / (t * (1.0 / CONTACT_UNITS)));
        add_terms(s.a, s.wa, 1.0, n, scale);
        add_terms(s.b, s.wb, -1.0, n, scale);
    }
}
