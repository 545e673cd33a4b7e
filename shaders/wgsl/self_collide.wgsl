//! include: state, hash, hash_fn
// self_collide — per particle: pushed out of every candidate closer than the thickness,
// its velocity into the contact removed; into pos_out, prev in place
// (core::cpu::self_collide::self_collide_at).
@group(0) @binding(5) var<storage, read_write> pos_out: array<vec4<f32>>;

// core::cpu::self_collide::candidates: outside the springs' 5 x 5 stencil and farther
// apart at rest than twice the thickness.
fn candidates(a: u32, b: u32) -> bool {
    let di = i32(a % p.n) - i32(b % p.n);
    let dj = i32(a / p.n) - i32(b / p.n);
    if abs(di) <= 2 && abs(dj) <= 2 {
        return false;
    }
    let t2 = 2.0 * p.self_thickness;
    return f32(di * di + dj * dj) * (p.spacing * p.spacing) > t2 * t2;
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
    var delta = vec3<f32>(0.0);
    for (var k = 0u; k < 27u; k++) {
        let cell = c + vec3<i32>(i32(k % 3u) - 1, i32((k / 3u) % 3u) - 1, i32(k / 9u) - 1);
        let b = bucket(cell, size);
        let start = min(cells[4u * b + 1u], np);
        let end = min(start + cells[4u * b], np);
        for (var s = start; s < end; s++) {
            let q = sorted[4u * s + 1u];
            if q == i || q >= np {
                continue;
            }
            let y4 = pos[q];
            if any(cell_of(y4.xyz) != cell) {
                continue;
            }
            let e = x4.xyz - y4.xyz;
            let d2 = e.x * e.x + e.y * e.y + e.z * e.z;
            if d2 >= t * t || d2 < 1e-12 || !candidates(i, q) {
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
