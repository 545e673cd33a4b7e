// The self-collision response (self_collide.wgsl on a grid, self_collide_mesh.wgsl on a
// mesh): everything but `contact(m, w, close)`, which each kernel defines — whether the
// particle whose slot word is w, `close` to m (within the thickness), may push it — and
// `other_mobility(w, hit)`, that particle's pos.w.
@group(0) @binding(5) var<storage, read_write> pos_out: array<vec4<f32>>;
// core::cpu::self_collide::{REACH, UNITS, MAX_CONTACTS}.
const REACH: f32 = 1.001;
const UNITS: f32 = 65536.0;
const MAX_CONTACTS: u32 = 32767u;

// One particle of the pair: where it is and what it has summed.
struct Mover {
    i: u32,
    x4: vec4<f32>,
    c: vec3<i32>,
    f: vec3<f32>,
    me: vec2<i32>,
    moving: bool,
    // The cells of the 3 x 3 x 3 around c that its sphere reaches: bit
    // (dx + 1) + 3 (dy + 1) + 9 (dz + 1).
    cells: u32,
    sum: vec3<i32>,
    contacts: u32,
    // Its velocity before the response, and Coulomb friction's sum (fixed point, units of
    // μs t / dt: friction_scale).
    v: vec3<f32>,
    rub: vec3<i32>,
}

// The cells of m's 3 x 3 x 3 that its sphere of radius REACH (cells) reaches: those whose
// squared distance from m's point, the sum of its squared gaps per axis, is below REACH².
// Any such superset of the cells within the thickness will do (see push); the CPU's
// reach computes the same set row by row.
fn reached_cells(m: Mover) -> u32 {
    let below = m.f * m.f;
    let above = (1.0 - m.f) * (1.0 - m.f);
    let r2 = REACH * REACH;
    var bits = 0u;
    for (var dz = 0u; dz < 3u; dz++) {
        let gz = select(select(0.0, below.z, dz == 0u), above.z, dz == 2u);
        for (var dy = 0u; dy < 3u; dy++) {
            let gyz = gz + select(select(0.0, below.y, dy == 0u), above.y, dy == 2u);
            let row = select(0u, 1u, gyz + below.x < r2) | select(0u, 2u, gyz < r2) | select(0u, 4u, gyz + above.x < r2);
            bits |= row << (3u * dy + 9u * dz);
        }
    }
    return bits;
}

// The three bits of m's reached cells in row (y, z) (bit dx + 1), none outside its 3 x 3.
fn row_bits(m: Mover, y: i32, z: i32) -> u32 {
    let dy = y - m.c.y;
    let dz = z - m.c.z;
    let inside = abs(dy) <= 1 && abs(dz) <= 1;
    return select(0u, (m.cells >> u32(3 * (dy + 1) + 9 * (dz + 1))) & 7u, inside);
}

// m's push from the particle in a slot (position y4, word w). Every entry of the walk
// counts: a particle closer than the thickness lies in a cell m's sphere reaches (REACH),
// whose bucket the walk reads once (no two of its rows share one); so m sums exactly its
// twin's contacts. Every other entry (of another row hashed to the same bucket, of a cell
// only the other mover reaches) is farther than t and pushes nothing.
fn push(m: ptr<function, Mover>, y4: vec4<f32>, w: u32) {
    let t = p.self_thickness;
    let e = (*m).x4.xyz - y4.xyz;
    let d2 = e.x * e.x + e.y * e.y + e.z * e.z;
    let close = d2 < t * t && d2 >= 1e-12;
    // The including kernel's: whether the particle in the slot may collide with m.
    let hit = contact(*m, w, close);
    (*m).contacts += select(0u, 1u, hit);
    let d = sqrt(d2);
    // The pair's share, the same at both ends (core::cpu::self_collide::pair_share); the
    // including kernel's other_mobility gives the slot's particle's pos.w.
    let share = min(1.0 / ((*m).x4.w + other_mobility(w, hit)), 1.0);
    // A miss adds 0 (its k may be infinite or NaN: not used).
    let k = select(0.0, (t - d) / d * share * (UNITS * p.inv_cell), hit);
    (*m).sum += vec3<i32>(e * k);
    // Coulomb friction (shared/self_friction.wgsl in the _friction kernels; nothing in
    // the others, shared/self_frictionless.wgsl: on lavapipe a branch not taken still
    // costs its body).
    rub(m, e, d2, t - d, share, w, hit);
}

// The rows of the 4 x 4 box from lo - 1 in (y, z) where m reaches a cell: bit
// (y - lo.y + 1) + 4 (z - lo.z + 1) (m's cell at most one from lo per axis).
fn box_rows(m: Mover, lo: vec3<i32>) -> u32 {
    var rows = 0u;
    for (var k = 0u; k < 9u; k++) {
        rows |= select(0u, 1u, ((m.cells >> (3u * k)) & 7u) != 0u) << (k % 3u + 4u * (k / 3u));
    }
    return rows << u32((m.c.y - lo.y) + 4 * (m.c.z - lo.z));
}

// The most rows one walk reads: the 4 x 4 around two cells at most one apart per axis.
const MAX_ROWS: u32 = 16u;

// The rows of cells that a's or b's sphere reaches, each read once for both: first their
// slot ranges, then one loop over all their entries. lavapipe steps 8 lanes together, and
// a loop runs as long as its longest lane: a loop per row ran twice the entries the lanes
// need on the settled heap, one loop over all runs 1.25 times (self_collision_probe counts
// both).
fn walk(a: ptr<function, Mover>, b: ptr<function, Mover>) {
    let size = table_size();
    let np = num_particles();
    let far = vec3<i32>(1000000000);
    let ca = (*a).c;
    let cb = (*b).c;
    let lo = min(select(far, ca, (*a).moving), select(far, cb, (*b).moving));
    // The ranges in registers, four vec4s each (an array indexed per lane costs lavapipe a
    // memory access per lane).
    var st0 = vec4<u32>(0u);
    var st1 = vec4<u32>(0u);
    var st2 = vec4<u32>(0u);
    var st3 = vec4<u32>(0u);
    var ln0 = vec4<u32>(0u);
    var ln1 = vec4<u32>(0u);
    var ln2 = vec4<u32>(0u);
    var ln3 = vec4<u32>(0u);
    let lane = vec4<u32>(0u, 1u, 2u, 3u);
    var rows = 0u;
    var total = 0u;
    // core::cpu::self_collide::row_ranges: a row whose buckets wrap around the table's
    // end is two ranges, [start, np) and [cells[0], end): walked as one, past np wrapped.
    // (A batch's world reads its own table, from table_base, whose words are slots from
    // world_base: taken back to the world's own here, and added again at the reads.)
    let tb = table_base();
    let wrap = min(cells[tb] - world_base, np);
    // Only the rows of the box that a mover reaches, one iteration each.
    var todo = box_rows(*a, lo) | box_rows(*b, lo);
    while todo != 0u {
        let r = firstTrailingBit(todo);
        todo &= todo - 1u;
        let y = lo.y - 1 + i32(r & 3u);
        let z = lo.z - 1 + i32(r >> 2u);
        {
            // The row's reached cells as bits of x - lo.x + 1 (b's cell at most one from a's).
            let bits = (row_bits(*a, y, z) << u32((*a).c.x - lo.x)) | (row_bits(*b, y, z) << u32((*b).c.x - lo.x));
            let first_x = lo.x - 1 + i32(firstTrailingBit(bits));
            let last_x = lo.x - 1 + i32(firstLeadingBit(bits));
            let first = bucket(vec3<i32>(first_x, y, z), size);
            let stop = first + u32(last_x - first_x) + 1u;
            let start = min(cells[tb + first] - world_base, np);
            // One read for the end (both sides of a branch run on lavapipe, reads too).
            let wraps = stop > size;
            let at_end = cells[tb + select(min(stop, size - 1u), stop - size, wraps)] - world_base;
            let len = select(
                clamp(select(at_end, np, stop == size), start, np) - start,
                np - start + clamp(at_end, wrap, np) - wrap,
                wraps
            );
            if len > 0u && rows < MAX_ROWS {
                let at = vec4<u32>(rows) - lane;
                st0 = select(st0, vec4<u32>(start), at == vec4<u32>(0u));
                st1 = select(st1, vec4<u32>(start), at == vec4<u32>(4u));
                st2 = select(st2, vec4<u32>(start), at == vec4<u32>(8u));
                st3 = select(st3, vec4<u32>(start), at == vec4<u32>(12u));
                ln0 = select(ln0, vec4<u32>(len), at == vec4<u32>(0u));
                ln1 = select(ln1, vec4<u32>(len), at == vec4<u32>(4u));
                ln2 = select(ln2, vec4<u32>(len), at == vec4<u32>(8u));
                ln3 = select(ln3, vec4<u32>(len), at == vec4<u32>(12u));
                rows += 1u;
                total += len;
            }
        }
    }
    var r = 0u;
    var base = 0u;
    var cur = st0.x;
    var len = ln0.x;
    for (var k = 0u; k < total; k++) {
        if k - base == len {
            base += len;
            r += 1u;
            let b2 = (r & 4u) != 0u;
            let b3 = (r & 8u) != 0u;
            let sv = select(select(st0, st1, b2), select(st2, st3, b2), b3);
            let lv = select(select(ln0, ln1, b2), select(ln2, ln3, b2), b3);
            let sh = select(sv.xy, sv.zw, (r & 2u) != 0u);
            let lh = select(lv.xy, lv.zw, (r & 2u) != 0u);
            cur = select(sh.x, sh.y, (r & 1u) != 0u);
            len = select(lh.x, lh.y, (r & 1u) != 0u);
        }
        let s0 = cur + (k - base);
        let s = select(s0, s0 - np + wrap, s0 >= np);
        let y4 = slot_pos[world_base + s];
        let w = bitcast<u32>(y4.w);
        push(a, y4, w);
        push(b, y4, w);
    }
}

// Particle i (at grid point (col, j) on a grid).
fn mover(i: u32, col: u32, j: u32, valid: bool) -> Mover {
    var m: Mover;
    m.i = i;
    m.moving = false;
    m.cells = 0u;
    m.sum = vec3<i32>(0);
    m.contacts = 0u;
    m.rub = vec3<i32>(0);
    // Past the grid's end (an odd n's last column) a particle that stays.
    m.x4 = pos[world_base + min(i, num_particles() - 1u)];
    m.v = vel[world_base + min(i, num_particles() - 1u)].xyz;
    m.moving = valid && m.x4.w != 0.0 && i32(i) != p.grab_index;
    let v = scaled(m.x4.xyz);
    m.c = cell_of(m.x4.xyz);
    m.f = v - floor(v);
    m.me = vec2<i32>(i32(col), i32(j));
    m.cells = select(0u, reached_cells(m), m.moving);
    return m;
}

// The push summed into m's position, and into its velocity as motion.
fn finish(m: Mover) {
    let x4 = m.x4;
    let i = m.i;
    let t = p.self_thickness;
    // Each end moves by its own mobility times the pair's share: by inverse mass.
    let delta = vec3<f32>(m.sum) * (t * (1.0 / UNITS)) * x4.w;
    let dd = delta.x * delta.x + delta.y * delta.y + delta.z * delta.z;
    // Coulomb friction's velocity, by inverse mass as the push; the position moves back
    // by it times dt (no creep).
    let c = FRICTION && coulomb();
    let fr = select(vec3<f32>(0.0), vec3<f32>(m.rub) * (mu_static() * t * (1.0 / UNITS) * (1.0 / p.dt)) * x4.w, c);
    let pushed = m.moving && m.contacts <= MAX_CONTACTS && (dd != 0.0 || any(fr != vec3<f32>(0.0)));
    // One site per buffer, values chosen by select: lavapipe walks the lanes of every
    // load and store site in the code, taken or not.
    let x = select(x4.xyz, x4.xyz + select(delta, delta - fr * p.dt, c), pushed);
    pos_out[world_base + i] = vec4<f32>(x, x4.w);
    // The push as motion: v += Δx / dt (core::cpu::self_collide::self_collide_at).
    if pushed {
        let v4 = vel[world_base + i];
        let u = v4.xyz + delta * (1.0 / p.dt);
        vel[world_base + i] = vec4<f32>(select(u, u - fr, c), v4.w);
    }
}

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let g = flat_id(id, groups);
    // A grid's pairs are row neighbours; a mesh's one row of its particles in list order.
    let width = block_width_of(p);
    let half = (width + 1u) / 2u;
    let j = g / half;
    if j >= block_rows_of(p) {
        return;
    }
    let col = 2u * (g % half);
    var a = mover(j * width + col, col, j, true);
    var b = mover(j * width + col + 1u, col + 1u, j, col + 1u < width);
    // Cells farther apart (a stretched or torn cloth, 0.1 % of the settled heap's pairs):
    // b sits out the pair's walk and walks alone after it. (lavapipe runs the body of an
    // if, and once each loop in it, whether a lane takes it or not: one walk here instead
    // of one for each mover saves every pair 3 % of the response.)
    let apart = any(abs(a.c - b.c) > vec3<i32>(1)) && a.moving && b.moving;
    var pb = b;
    pb.moving = pb.moving && !apart;
    pb.cells = select(pb.cells, 0u, apart);
    walk(&a, &pb);
    if apart {
        var none = pb;
        none.moving = false;
        none.cells = 0u;
        walk(&b, &none);
    } else {
        b = pb;
    }
    finish(a);
    if col + 1u < width {
        finish(b);
    }
}
