//! include: state, hash, hash_fn
// self_collide — per particle: pushed out of every candidate closer than the thickness,
// its velocity into the contact removed; into pos_out, prev in place
// (core::cpu::self_collide::self_collide_at).
@group(0) @binding(5) var<storage, read_write> pos_out: array<vec4<f32>>;

// core::cpu::self_collide::{REACH, UNITS, MAX_CONTACTS}.
const REACH: f32 = 1.001;
const UNITS: f32 = 65536.0;
const MAX_CONTACTS: u32 = 32767u;

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

// core::cpu::self_collide::gap: the distance (cells) to the neighbour cell at offset d.
fn gap(f: f32, d: i32) -> f32 {
    if d == 0 {
        return 0.0;
    }
    return select(1.0 - f, f, d < 0);
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
    if x4.w == 0.0 || i32(i) == p.grab_index {
        pos_out[i] = x4;
        return;
    }
    let t = p.self_thickness;
    let size = table_size();
    let v = scaled(x4.xyz);
    let cf = floor(v);
    let c = vec3<i32>(cf);
    let f = v - cf;
    let me = vec2<i32>(i32(i % p.n), i32(i / p.n));
    let scale = UNITS * p.inv_cell;
    var sum = vec3<i32>(0);
    var contacts = 0u;
    for (var dz = -1; dz <= 1; dz++) {
        for (var dy = -1; dy <= 1; dy++) {
            // core::cpu::self_collide::rows_around: the rows the sphere reaches, trimmed.
            let gy = gap(f.y, dy);
            let gz = gap(f.z, dz);
            let r2 = REACH * REACH - gy * gy - gz * gz;
            if r2 <= 0.0 {
                continue;
            }
            let r = sqrt(r2);
            let lo = c.x - select(0, 1, f.x < r);
            let hi = c.x + select(0, 1, 1.0 - f.x < r);
            let first = bucket(vec3<i32>(lo, c.y + dy, c.z + dz), size);
            let tag = row_tag(c.y + dy, c.z + dz);
            let stop = first + u32(hi - lo) + 1u;
            // core::cpu::self_collide::row_ranges: one range, or two where the row's
            // buckets wrap around the table's end; walked as one.
            let start0 = min(cells[first], np);
            var end0 = np;
            var start1 = 0u;
            var end1 = 0u;
            if stop <= size {
                if stop < size {
                    end0 = cells[stop];
                }
                end0 = clamp(end0, start0, np);
            } else {
                start1 = min(cells[0], np);
                end1 = clamp(cells[stop - size], start1, np);
            }
            let n0 = end0 - start0;
            let total = n0 + (end1 - start1);
            for (var k = 0u; k < total; k++) {
                let s = select(start1 + (k - n0), start0 + k, k < n0);
                // Foreign rows and grid neighbours refused by the slot's word.
                let y4 = slot_pos[s];
                let w = bitcast<u32>(y4.w);
                if ((w >> (2u * COORD_BITS)) & 127u) != tag {
                    continue;
                }
                let qc = vec2<u32>(w & COORD_MASK, (w >> COORD_BITS) & COORD_MASK);
                if !candidates(me, vec2<i32>(qc)) {
                    continue;
                }
                let e = x4.xyz - y4.xyz;
                let d2 = e.x * e.x + e.y * e.y + e.z * e.z;
                if d2 >= t * t || d2 < 1e-12 {
                    continue;
                }
                contacts += 1u;
                let d = sqrt(d2);
                let share = select(0.5, 1.0, (w & PINNED) != 0u);
                let push = (t - d) / d * share * scale;
                sum += vec3<i32>(e * push);
            }
        }
    }
    if contacts > MAX_CONTACTS {
        pos_out[i] = x4;
        return;
    }
    let delta = vec3<f32>(sum) * (t * (1.0 / UNITS));
    let dd = delta.x * delta.x + delta.y * delta.y + delta.z * delta.z;
    if dd == 0.0 {
        pos_out[i] = x4;
        return;
    }
    // The previous position only where pushed (one particle in several).
    let xp4 = prev[i];
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
