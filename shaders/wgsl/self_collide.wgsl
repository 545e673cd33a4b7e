//! include: state, hash, hash_fn
// self_collide — per particle: pushed out of every candidate closer than the thickness,
// its velocity into the contact removed; into pos_out, prev in place
// (core::cpu::self_collide::self_collide_at).
@group(0) @binding(5) var<storage, read_write> pos_out: array<vec4<f32>>;

// core::cpu::self_collide::candidate_coords: outside the springs' 5 x 5 stencil and
// farther apart at rest than twice the thickness.
fn candidates(a: vec2<i32>, b: vec2<i32>) -> bool {
    let d = a - b;
    if abs(d.x) <= 2 && abs(d.y) <= 2 {
        return false;
    }
    let t2 = 2.0 * p.self_thickness;
    return f32(d.x * d.x + d.y * d.y) * (p.spacing * p.spacing) > t2 * t2;
}

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    let np = num_particles();
    if i >= np {
        return;
    }
    let x4 = pos[i];
    let xp4 = prev[i];
    if x4.w == 0.0 || i32(i) == p.grab_index {
        pos_out[i] = x4;
        return;
    }
    let t = p.self_thickness;
    let size = table_size();
    let c = cell_of(x4.xyz);
    // Per axis the neighbour cell on the point's side (core::cpu::self_collide::sides).
    let v = clamp(x4.xyz * p.inv_cell, vec3<f32>(-CELL_LIMIT), vec3<f32>(CELL_LIMIT));
    let side = select(vec3<i32>(-1), vec3<i32>(1), v - vec3<f32>(c) >= vec3<f32>(0.5));
    let me = vec2<i32>(i32(i % p.n), i32(i / p.n));
    var buckets: array<u32, 8>;
    var delta = vec3<f32>(0.0);
    for (var k = 0u; k < 8u; k++) {
        let cell = c + select(vec3<i32>(0), side, (vec3<u32>(k) >> vec3<u32>(0u, 1u, 2u) & vec3<u32>(1u)) == vec3<u32>(1u));
        let b = bucket(cell, size);
        buckets[k] = b;
        // Two of the 8 cells may share a bucket: each bucket once.
        var seen = false;
        for (var m = 0u; m < k; m++) {
            seen = seen || buckets[m] == b;
        }
        if seen {
            continue;
        }
        let start = min(cells[4u * b + 1u], np);
        let end = min(start + cells[4u * b], np);
        if start == end {
            continue;
        }
        // A bucket whose particles are all grid neighbours (its bounding box within the
        // stencil: most of a flat cloth's) is skipped unread.
        let mask = (1u << COORD_BITS) - 1u;
        let lo_w = cells[4u * b + 2u];
        let hi_w = cells[4u * b + 3u];
        let lo = vec2<i32>(vec2<u32>(lo_w & mask, lo_w >> COORD_BITS));
        let hi = vec2<i32>(vec2<u32>(hi_w & mask, hi_w >> COORD_BITS));
        if all(lo >= me - vec2<i32>(2)) && all(hi <= me + vec2<i32>(2)) {
            continue;
        }
        for (var s = start; s < end; s++) {
            // Grid neighbours refused by the slot's coordinates before loading them.
            let w = sorted[4u * s + 1u];
            let qc = vec2<u32>(w & ((1u << COORD_BITS) - 1u), w >> COORD_BITS);
            let q = qc.y * p.n + qc.x;
            if qc.x >= p.n || q >= np || !candidates(me, vec2<i32>(qc)) {
                continue;
            }
            let y4 = pos[q];
            let e = x4.xyz - y4.xyz;
            let d2 = e.x * e.x + e.y * e.y + e.z * e.z;
            if d2 >= t * t || d2 < 1e-12 {
                continue;
            }
            let d = sqrt(d2);
            let share = select(0.5, 1.0, y4.w == 0.0);
            delta += e * ((t - d) / d * share);
        }
    }
    let dd = delta.x * delta.x + delta.y * delta.y + delta.z * delta.z;
    if dd == 0.0 {
        pos_out[i] = x4;
        return;
    }
    let x = x4.xyz + delta;
    var u = x4.xyz - xp4.xyz;
    let nrm = delta / sqrt(dd);
    let un = u.x * nrm.x + u.y * nrm.y + u.z * nrm.z;
    if un < 0.0 {
        u -= un * nrm;
    }
    pos_out[i] = vec4<f32>(x, x4.w);
    prev[i] = vec4<f32>(x - u, xp4.w);
}
