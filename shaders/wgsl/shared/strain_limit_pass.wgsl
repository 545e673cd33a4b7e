// The strain limit's pass (strain_limit.wgsl, strain_limit_count.wgsl): everything but
// `strained`, which each kernel defines: what it does with a particle's corrected point
// after storing it.
@group(0) @binding(0) var<uniform> step_params: StepParams;
// Copied from step_params by the kernel's first statement (see shared/state.wgsl).
var<private> p: StepParams;
@group(0) @binding(1) var<storage, read_write> pos: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> vel: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> pos_out: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read> tethers: array<Tether>;
@group(0) @binding(16) var<uniform> interior_slots: InteriorSlots;
var<private> interior: InteriorSlots;

// Mobility of particle k with pos[k].w = w: 0 when pinned or grabbed.
fn mobility(k: u32, w: f32) -> f32 {
    if i32(k) == p.grab_index {
        return 0.0;
    }
    return w;
}

// The correction sum and count of the springs over their limit.
struct Correction {
    sum: vec3<f32>,
    count: f32,
}

// Adds the share of the spring to particle b at xb4 (rest length `rest`) to c when it is
// stretched past the limit; xi and wi are the particle's position and mobility.
fn limit_spring(c: ptr<function, Correction>, b: u32, xb4: vec4<f32>, rest: f32, xi: vec3<f32>, wi: f32) {
    let stretch = 1.0 + p.strain_limit;
    let aim = 1.0 + STRAIN_AIM * p.strain_limit;
    let d = xb4.xyz - xi;
    let len = len3(d);
    if len > stretch * rest {
        let wb = mobility(b, xb4.w);
        (*c).sum += d * (wi * (len - aim * rest) / ((wi + wb) * len));
        (*c).count += 1.0;
    }
}

// Grid point (c, r): its particle (particle 0 when outside the grid, so that every lane
// loads something), that particle's pos, and whether it is inside.
struct Gp {
    k: u32,
    x4: vec4<f32>,
    inside: bool,
}

fn grid_point(c: i32, r: i32) -> Gp {
    let n = i32(p.n);
    let inside = c >= 0 && c < n && r >= 0 && r < n;
    let k = u32(select(0, r * n + c, inside));
    return Gp(k, pos[k], inside);
}

fn limit_grid(c: ptr<function, Correction>, b: Gp, s: u32, xi: vec3<f32>, wi: f32) {
    if b.inside {
        limit_spring(c, b.k, b.x4, interior.slots[s].rest, xi, wi);
    }
}

// The corrected position of particle i (at x4, mobility wi) from correction c, pulled back
// by its tethers; x4 itself when it does not move (wi = 0).
fn finish(i: u32, x4: vec4<f32>, wi: f32, c: Correction) -> vec4<f32> {
    var x = x4.xyz;
    if c.count > 0.0 {
        x = x4.xyz + c.sum / c.count;
    }
    let stretch = 1.0 + p.strain_limit;
    for (var t = 0u; t < TETHER_SLOTS; t++) {
        let tether = tethers[i * TETHER_SLOTS + t];
        let pin = pos[u32(max(tether.pin, 0))].xyz;
        let d = x - pin;
        let len = len3(d);
        let max_len = stretch * tether.rest;
        if tether.pin >= 0 && len > max_len {
            x = pin + d * (max_len / len);
        }
    }
    return select(vec4<f32>(x, x4.w), x4, wi == 0.0);
}

// Stores particle k's corrected point `out` (from x4) and the velocity its move implies
// (core::cpu::strain_limit::strain_vel: v += (out − x)·(1/dt)).
fn store_point(k: u32, x4: vec4<f32>, out: vec4<f32>) {
    pos_out[k] = out;
    vel[k] = vec4<f32>(vel[k].xyz + (out.xyz - x4.xyz) * (1.0 / p.dt), 0.0);
    strained(k, out);
}

// Particle (row, col) of a block: a its point, s0 … s7 its neighbours in slot order
// (core::grid::SLOT_OFFSETS).
fn block_particle(row: u32, col: u32, a: Gp, s0: Gp, s1: Gp, s2: Gp, s3: Gp, s4: Gp, s5: Gp, s6: Gp, s7: Gp) {
    let xi = a.x4.xyz;
    let wi = mobility(a.k, a.x4.w);
    var c = Correction(vec3<f32>(0.0), 0.0);
    limit_grid(&c, s0, 0u, xi, wi);
    limit_grid(&c, s1, 1u, xi, wi);
    limit_grid(&c, s2, 2u, xi, wi);
    limit_grid(&c, s3, 3u, xi, wi);
    limit_grid(&c, s4, 4u, xi, wi);
    limit_grid(&c, s5, 5u, xi, wi);
    limit_grid(&c, s6, 6u, xi, wi);
    limit_grid(&c, s7, 7u, xi, wi);
    let out = finish(a.k, a.x4, wi, c);
    if a.inside && interior.enabled != 0u {
        store_point(a.k, a.x4, out);
    }
}

// Particle i from its table (an irregular table).
fn table_particle(i: u32) {
    let x4 = pos[i];
    let wi = mobility(i, x4.w);
    var c = Correction(vec3<f32>(0.0), 0.0);
    for (var s = 0u; s < STRAIN_SLOTS; s++) {
        let slot = slot_at(i, s);
        if slot.neighbor >= 0 {
            let b = u32(slot.neighbor);
            limit_spring(&c, b, pos[b], slot.rest, x4.xyz, wi);
        }
    }
    let out = finish(i, x4, wi, c);
    store_point(i, x4, out);
}

// Grid point (c, r), which the lane on the left (right) holds as `theirs`: passed by a
// subgroup shuffle where the flavor has them and that lane holds the block beside,
// loaded otherwise (see shared/window_sh.wgsl).
fn left_point(theirs: Gp, c: i32, r: i32) -> Gp {
    let x4 = from_left4(theirs.x4);
    let n = i32(p.n);
    if have_left() {
        let inside = c >= 0 && c < n && r >= 0 && r < n;
        return Gp(u32(select(0, r * n + c, inside)), x4, inside);
    }
    return grid_point(c, r);
}

fn right_point(theirs: Gp, c: i32, r: i32) -> Gp {
    let x4 = from_right4(theirs.x4);
    let n = i32(p.n);
    if have_right() {
        let inside = c >= 0 && c < n && r >= 0 && r < n;
        return Gp(u32(select(0, r * n + c, inside)), x4, inside);
    }
    return grid_point(c, r);
}

// Block b at (row, c0) on the regular grid: the window of rows j - 1 … j + 1 loaded once
// — or, with shuffles, its own 12 points loaded and the 6 beside passed.
fn grid_block(b: u32, row: u32, c0: u32) {
    window_start(b, (p.n + BLOCK - 1u) / BLOCK);
    let r = i32(row);
    let c = i32(c0);
    // Rows j - 1, j, j + 1: columns c - 1 … c + 4, the block's own first.
    let u1 = grid_point(c, r - 1);
    let u2 = grid_point(c + 1, r - 1);
    let u3 = grid_point(c + 2, r - 1);
    let u4 = grid_point(c + 3, r - 1);
    let m1 = grid_point(c, r);
    let m2 = grid_point(c + 1, r);
    let m3 = grid_point(c + 2, r);
    let m4 = grid_point(c + 3, r);
    let d1 = grid_point(c, r + 1);
    let d2 = grid_point(c + 1, r + 1);
    let d3 = grid_point(c + 2, r + 1);
    let d4 = grid_point(c + 3, r + 1);
    let u0 = left_point(u4, c - 1, r - 1);
    let u5 = right_point(u1, c + 4, r - 1);
    let m0 = left_point(m4, c - 1, r);
    let m5 = right_point(m1, c + 4, r);
    let d0 = left_point(d4, c - 1, r + 1);
    let d5 = right_point(d1, c + 4, r + 1);
    // Particle k (at m[k + 1]), slots (-1,0) (1,0) (0,-1) (0,1) (-1,-1) (1,-1) (-1,1) (1,1)
    // = m[k] m[k+2] u[k+1] d[k+1] u[k] u[k+2] d[k] d[k+2].
    block_particle(row, c0, m1, m0, m2, u1, d1, u0, u2, d0, d2);
    block_particle(row, c0 + 1u, m2, m1, m3, u2, d2, u1, u3, d1, d3);
    block_particle(row, c0 + 2u, m3, m2, m4, u3, d3, u2, u4, d2, d4);
    block_particle(row, c0 + 3u, m4, m3, m5, u4, d4, u3, u5, d3, d5);
}

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    interior = interior_slots;
    let b = flat_id(id, groups);
    let rows = block_rows_of(p);
    let width = block_width_of(p);
    let origin = block_origin(b, width);
    let row = origin.x;
    let c0 = origin.y;
    // A uniform branch: each table mode does only its own loads.
    if interior.enabled != 0u {
        grid_block(b, row, c0);
        return;
    }
    // The table: storage buffers or the image (an irregular table, or table=storage|image).
    for (var k = 0u; k < BLOCK; k++) {
        if row < rows && c0 + k < width {
            table_particle(row * width + c0 + k);
        }
    }
}
