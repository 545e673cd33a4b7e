// The strain limit's pass down a strip (`strain_counts=strip`): an invocation takes a
// block's BLOCK columns through STRIP_ROWS rows of a regular grid, carrying from row to row
// the positions of three rows (columns c0 - 2 … c0 + 5), the lengths of the springs
// between them and the counts of the points around its block. Every spring's length is
// computed once, for the counts of both its ends and for the pass (a length is the same
// from either end: len3 of -d is len3 of d, bit for bit), and every count once: per row,
// 27 lengths for four particles, where the pass that counts inline computes its four
// particles' 32 and, for each spring over its limit, the eight of the neighbour's count.
// The same lengths, comparisons, counts and corrections as
// core::cpu::strain_limit::count_at and limit_at, in the same order: the same bits. An
// irregular table (a mesh, or table=storage|image) walks each particle's row as
// shared/strain_limit_pass.wgsl's table_particle does, the strip's rows one by one.

// A row of the strip's window: columns c0 - 2 … c0 + 5 (index 0 … 7), each point's
// position (particle 0's where it lies outside the grid, so that every lane loads
// something) and whether it is inside.
struct StripRow {
    x: array<vec4<f32>, 8>,
    inside: array<bool, 8>,
}

// The lengths of the springs from a row down to the next: at index j, from column j to
// column j (`v`), j + 1 (`r`) and j - 1 (`l`); 0 where either end lies outside the grid
// (never over a limit, as the blocked pass skips such a neighbour).
struct Down {
    v: array<f32, 8>,
    r: array<f32, 8>,
    l: array<f32, 8>,
}

// The strip's functions index their arrays by constants only (no loops over them): so
// that the drivers keep the rows in registers, wgpu's bounded loops included.
fn strip_row(r: i32, c: i32) -> StripRow {
    let g0 = grid_point(c, r);
    let g1 = grid_point(c + 1, r);
    let g2 = grid_point(c + 2, r);
    let g3 = grid_point(c + 3, r);
    let g4 = grid_point(c + 4, r);
    let g5 = grid_point(c + 5, r);
    let g6 = grid_point(c + 6, r);
    let g7 = grid_point(c + 7, r);
    return StripRow(
        array<vec4<f32>, 8>(g0.x4, g1.x4, g2.x4, g3.x4, g4.x4, g5.x4, g6.x4, g7.x4),
        array<bool, 8>(g0.inside, g1.inside, g2.inside, g3.inside, g4.inside, g5.inside, g6.inside, g7.inside)
    );
}

// The length from point i of row a to point j of row b (the same row or the next), 0
// unless both are inside.
fn strip_len(a: StripRow, i: i32, b: StripRow, j: i32) -> f32 {
    return select(0.0, len3(b.x[j].xyz - a.x[i].xyz), a.inside[i] && b.inside[j]);
}

// The lengths along a row: at index j, from column j to j + 1 (j = 0 … 6).
fn across(a: StripRow) -> array<f32, 8> {
    return array<f32, 8>(
        strip_len(a, 0, a, 1),
        strip_len(a, 1, a, 2),
        strip_len(a, 2, a, 3),
        strip_len(a, 3, a, 4),
        strip_len(a, 4, a, 5),
        strip_len(a, 5, a, 6),
        strip_len(a, 6, a, 7),
        0.0
    );
}

// The lengths down from row a to row b at columns 1 … 6 (`v`), 0 … 6 (`r`) and 1 … 7
// (`l`): what the counts of columns 1 … 6 and the pass of columns 2 … 5 read.
fn down(a: StripRow, b: StripRow) -> Down {
    return Down(
        array<f32, 8>(
            0.0,
            strip_len(a, 1, b, 1),
            strip_len(a, 2, b, 2),
            strip_len(a, 3, b, 3),
            strip_len(a, 4, b, 4),
            strip_len(a, 5, b, 5),
            strip_len(a, 6, b, 6),
            0.0
        ),
        array<f32, 8>(
            strip_len(a, 0, b, 1),
            strip_len(a, 1, b, 2),
            strip_len(a, 2, b, 3),
            strip_len(a, 3, b, 4),
            strip_len(a, 4, b, 5),
            strip_len(a, 5, b, 6),
            strip_len(a, 6, b, 7),
            0.0
        ),
        array<f32, 8>(
            0.0,
            strip_len(a, 1, b, 0),
            strip_len(a, 2, b, 1),
            strip_len(a, 3, b, 2),
            strip_len(a, 4, b, 3),
            strip_len(a, 5, b, 4),
            strip_len(a, 6, b, 5),
            strip_len(a, 7, b, 6)
        )
    );
}

// A spring of slot s of length len: 1 over its limit, else 0 (shared/strain_fn.wgsl's `over`).
fn over_len(len: f32, s: u32) -> f32 {
    return select(0.0, 1.0, len > (1.0 + p.strain_limit) * interior.slots[s].rest);
}

// The eight lengths of point j of a row, in slot order (core::grid::SLOT_OFFSETS:
// (-1,0) (1,0) (0,-1) (0,1) (-1,-1) (1,-1) (-1,1) (1,1) as (column, row) offsets): h the
// row's lengths along it, up the row above's lengths down to it, dn its own down.
fn slot_lens(j: i32, h: array<f32, 8>, up: Down, dn: Down) -> array<f32, 8> {
    return array<f32, 8>(h[j - 1], h[j], up.v[j], dn.v[j], up.r[j - 1], up.l[j + 1], dn.l[j], dn.r[j]);
}

// The count of point j of a row (core::cpu::strain_limit::count_at, added in slot order as
// shared/strain_count_fn.wgsl's count_block adds them).
fn strip_count(j: i32, h: array<f32, 8>, up: Down, dn: Down) -> f32 {
    let l = slot_lens(j, h, up, dn);
    var c = over_len(l[0], 0u);
    c += over_len(l[1], 1u);
    c += over_len(l[2], 2u);
    c += over_len(l[3], 3u);
    c += over_len(l[4], 4u);
    c += over_len(l[5], 5u);
    c += over_len(l[6], 6u);
    c += over_len(l[7], 7u);
    return c;
}

// The counts of a row's points at columns 1 … 6.
fn strip_counts(h: array<f32, 8>, up: Down, dn: Down) -> array<f32, 8> {
    return array<f32, 8>(
        0.0,
        strip_count(1, h, up, dn),
        strip_count(2, h, up, dn),
        strip_count(3, h, up, dn),
        strip_count(4, h, up, dn),
        strip_count(5, h, up, dn),
        strip_count(6, h, up, dn),
        0.0
    );
}

// Adds the share of slot s's spring (length len, rest rest) to the particle at xi (index
// k, mobility wi, count ci), its neighbour b at xb with count cb, when it is over its limit
// (shared/strain_fn.wgsl's limit_spring with the length known).
fn strip_spring(c: ptr<function, Correction>, len: f32, rest: f32, b: u32, xb: vec4<f32>, cb: f32, xi: vec3<f32>, wi: f32, ci: f32) {
    let stretch = 1.0 + p.strain_limit;
    let aim = 1.0 + STRAIN_AIM * p.strain_limit;
    if len > stretch * rest {
        let wb = mobility(b, xb.w);
        let d = xb.xyz - xi;
        (*c).sum += d * (wi * (len - aim * rest) / ((wi + wb) * len * max(max(ci, cb), 1.0)));
        (*c).count += 1.0;
    }
}

// The pass for the block's particle at column j (2 … 5) of row r's window m, u and d the
// rows above and below, h the lengths along m, dm and du the lengths down from m and from
// u, cu, cm and cd the three rows' counts.
fn strip_particle(
    j: i32,
    r: i32,
    c: i32,
    u: StripRow,
    m: StripRow,
    d: StripRow,
    h: array<f32, 8>,
    du: Down,
    dm: Down,
    cu: array<f32, 8>,
    cm: array<f32, 8>,
    cd: array<f32, 8>
) {
    if !m.inside[j] {
        return;
    }
    let n = i32(p.n);
    let k = r * n + c + j;
    let x4 = m.x[j];
    let xi = x4.xyz;
    let wi = mobility(u32(k), x4.w);
    let ci = cm[j];
    var corr = Correction(vec3<f32>(0.0), 0.0);
    // A count of 0: none of the particle's springs is over its limit.
    if ci > 0.0 {
        let l = slot_lens(j, h, du, dm);
        strip_spring(&corr, l[0], interior.slots[0].rest, u32(k - 1), m.x[j - 1], cm[j - 1], xi, wi, ci);
        strip_spring(&corr, l[1], interior.slots[1].rest, u32(k + 1), m.x[j + 1], cm[j + 1], xi, wi, ci);
        strip_spring(&corr, l[2], interior.slots[2].rest, u32(k - n), u.x[j], cu[j], xi, wi, ci);
        strip_spring(&corr, l[3], interior.slots[3].rest, u32(k + n), d.x[j], cd[j], xi, wi, ci);
        strip_spring(&corr, l[4], interior.slots[4].rest, u32(k - n - 1), u.x[j - 1], cu[j - 1], xi, wi, ci);
        strip_spring(&corr, l[5], interior.slots[5].rest, u32(k - n + 1), u.x[j + 1], cu[j + 1], xi, wi, ci);
        strip_spring(&corr, l[6], interior.slots[6].rest, u32(k + n - 1), d.x[j - 1], cd[j - 1], xi, wi, ci);
        strip_spring(&corr, l[7], interior.slots[7].rest, u32(k + n + 1), d.x[j + 1], cd[j + 1], xi, wi, ci);
    }
    store_point(u32(k), x4, finish(u32(k), x4, wi, corr));
}

// The strip from row r0 at columns c0 … c0 + BLOCK - 1 of the regular grid.
fn grid_strip(r0: i32, c0: i32) {
    let c = c0 - 2;
    let end = min(r0 + i32(STRIP_ROWS), i32(p.n));
    var u = strip_row(r0 - 1, c);
    var m = strip_row(r0, c);
    var d = strip_row(r0 + 1, c);
    var du = down(u, m);
    var dm = down(m, d);
    var h = across(m);
    var hd = across(d);
    var cu = strip_counts(across(u), down(strip_row(r0 - 2, c), u), du);
    var cm = strip_counts(h, du, dm);
    for (var r = r0; r < end; r++) {
        let dd = strip_row(r + 2, c);
        let ddown = down(d, dd);
        let cd = strip_counts(hd, dm, ddown);
        strip_particle(2, r, c, u, m, d, h, du, dm, cu, cm, cd);
        strip_particle(3, r, c, u, m, d, h, du, dm, cu, cm, cd);
        strip_particle(4, r, c, u, m, d, h, du, dm, cu, cm, cd);
        strip_particle(5, r, c, u, m, d, h, du, dm, cu, cm, cd);
        u = m;
        m = d;
        d = dd;
        du = dm;
        dm = ddown;
        h = hd;
        hd = across(dd);
        cu = cm;
        cm = cd;
    }
}

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    interior = interior_slots;
    let s = flat_id(id, groups);
    let rows = block_rows_of(p);
    let width = block_width_of(p);
    let per_row = (width + BLOCK - 1u) / BLOCK;
    let strip = s / per_row;
    let c0 = (s - strip * per_row) * BLOCK;
    let r0 = strip * STRIP_ROWS;
    if r0 >= rows {
        return;
    }
    // A uniform branch: each table mode does only its own loads.
    if interior.enabled != 0u {
        grid_strip(i32(r0), i32(c0));
        return;
    }
    // The table: storage buffers or the image (an irregular table, or table=storage|image).
    for (var row = r0; row < min(r0 + STRIP_ROWS, rows); row++) {
        for (var k = 0u; k < BLOCK; k++) {
            if c0 + k < width {
                table_particle(row * width + c0 + k);
            }
        }
    }
}
