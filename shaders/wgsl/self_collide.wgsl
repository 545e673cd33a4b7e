//! include: state, hash, hash_fn
// self_collide — per pair of grid neighbours (i, i + 1) of a row: each pushed out of every
// candidate closer than the thickness, its velocity into the contact removed; into
// pos_out, prev in place (core::cpu::self_collide::self_collide_at, per particle there).
// The two share one walk over the rows of cells that either's sphere reaches, when their
// cells are neighbours (almost always: grid neighbours lie about a spacing apart): half the
// rows' reads, and each entry read once for both. Each particle still takes only the
// entries of the cells its own walk would read, so it sums what its twin sums; in fixed
// point, in any order, the same bits.
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

// One particle of the pair: where it is and what it has summed.
struct Mover {
    i: u32,
    x4: vec4<f32>,
    c: vec3<i32>,
    f: vec3<f32>,
    me: vec2<i32>,
    moving: bool,
    sum: vec3<i32>,
    contacts: u32,
}

// The cells in x of row (y, z) that m's sphere reaches (core::cpu::self_collide::
// rows_around), as [lo, hi]; empty (lo > hi) where it reaches none of them.
fn reach(m: Mover, y: i32, z: i32) -> vec2<i32> {
    let dy = y - m.c.y;
    let dz = z - m.c.z;
    if !m.moving || abs(dy) > 1 || abs(dz) > 1 {
        return vec2<i32>(1, 0);
    }
    let gy = gap(m.f.y, dy);
    let gz = gap(m.f.z, dz);
    let r2 = REACH * REACH - gy * gy - gz * gz;
    if r2 <= 0.0 {
        return vec2<i32>(1, 0);
    }
    let r = sqrt(r2);
    return vec2<i32>(m.c.x - select(0, 1, m.f.x < r), m.c.x + select(0, 1, 1.0 - m.f.x < r));
}

// m's push from the particle in a slot (position y4, word w, cell cx in x) of a row whose
// cells m reaches in xr.
fn push(m: ptr<function, Mover>, xr: vec2<i32>, y4: vec4<f32>, w: u32, cx: i32) {
    if cx < xr.x || cx > xr.y {
        return;
    }
    let qc = vec2<u32>(w & COORD_MASK, (w >> COORD_BITS) & COORD_MASK);
    if !candidates((*m).me, vec2<i32>(qc)) {
        return;
    }
    let t = p.self_thickness;
    let e = (*m).x4.xyz - y4.xyz;
    let d2 = e.x * e.x + e.y * e.y + e.z * e.z;
    if d2 >= t * t || d2 < 1e-12 {
        return;
    }
    (*m).contacts += 1u;
    let d = sqrt(d2);
    let share = select(0.5, 1.0, (w & PINNED) != 0u);
    let k = (t - d) / d * share * (UNITS * p.inv_cell);
    (*m).sum += vec3<i32>(e * k);
}

// The rows of cells that a's or b's sphere reaches, each read once for both.
fn walk(a: ptr<function, Mover>, b: ptr<function, Mover>) {
    let size = table_size();
    let np = num_particles();
    var lo = vec3<i32>(1000000000);
    var hi = vec3<i32>(-1000000000);
    if (*a).moving {
        lo = min(lo, (*a).c);
        hi = max(hi, (*a).c);
    }
    if (*b).moving {
        lo = min(lo, (*b).c);
        hi = max(hi, (*b).c);
    }
    for (var z = lo.z - 1; z <= hi.z + 1; z++) {
        for (var y = lo.y - 1; y <= hi.y + 1; y++) {
            let ra = reach(*a, y, z);
            let rb = reach(*b, y, z);
            let first_x = min(select(ra.x, 1000000000, ra.x > ra.y), select(rb.x, 1000000000, rb.x > rb.y));
            let last_x = max(select(ra.y, -1000000000, ra.x > ra.y), select(rb.y, -1000000000, rb.x > rb.y));
            if first_x > last_x {
                continue;
            }
            let tag = row_tag(y, z);
            let first = bucket(vec3<i32>(first_x, y, z), size);
            let stop = first + u32(last_x - first_x) + 1u;
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
                let y4 = slot_pos[s];
                let w = bitcast<u32>(y4.w);
                // Entries of other rows (their tag) refused for both.
                if ((w >> (2u * COORD_BITS)) & 127u) != tag {
                    continue;
                }
                let cx = cell_of(y4.xyz).x;
                push(a, ra, y4, w, cx);
                push(b, rb, y4, w, cx);
            }
        }
    }
}

fn mover(i: u32, valid: bool) -> Mover {
    var m: Mover;
    m.i = i;
    m.moving = false;
    m.sum = vec3<i32>(0);
    m.contacts = 0u;
    if !valid {
        return m;
    }
    m.x4 = pos[i];
    m.moving = m.x4.w != 0.0 && i32(i) != p.grab_index;
    let v = scaled(m.x4.xyz);
    m.c = cell_of(m.x4.xyz);
    m.f = v - floor(v);
    m.me = vec2<i32>(i32(i % p.n), i32(i / p.n));
    return m;
}

// The push summed into m's position and its velocity into the contact removed.
fn finish(m: Mover) {
    let x4 = m.x4;
    let i = m.i;
    if !m.moving || m.contacts > MAX_CONTACTS {
        pos_out[i] = x4;
        return;
    }
    let t = p.self_thickness;
    let delta = vec3<f32>(m.sum) * (t * (1.0 / UNITS));
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

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let g = flat_id(id, groups);
    let half = (p.n + 1u) / 2u;
    let j = g / half;
    if j >= p.n {
        return;
    }
    let col = 2u * (g % half);
    var a = mover(j * p.n + col, true);
    var b = mover(j * p.n + col + 1u, col + 1u < p.n);
    if all(abs(a.c - b.c) <= vec3<i32>(1)) || !a.moving || !b.moving {
        walk(&a, &b);
    } else {
        // Cells farther apart (a stretched or torn cloth): one walk each.
        var none = mover(0u, false);
        walk(&a, &none);
        walk(&b, &none);
    }
    finish(a);
    if col + 1u < p.n {
        finish(b);
    }
}
