// The strain limit's pass (strain_limit.wgsl, strain_limit_count.wgsl) over
// shared/strain_window.wgsl: everything but `strained`, which each kernel defines: what
// it does with a particle's corrected point after storing it. The counts it divides by
// come from shared/strain_counts_aux.wgsl (strain_count's, in aux0) or
// shared/strain_counts_inline.wgsl (computed here).
@group(0) @binding(2) var<storage, read_write> vel: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> pos_out: array<vec4<f32>>;

fn limit_grid(c: ptr<function, Correction>, b: Gp, s: u32, xi: vec3<f32>, wi: f32, ci: f32) {
    if b.inside {
        let rest = interior.slots[s].rest;
        // The neighbour's count only for a spring over its limit: limit_spring adds
        // nothing for the others.
        var cb = 0.0;
        if over(xi, b.x4, rest) != 0.0 {
            cb = grid_neighbour_count(b);
        }
        limit_spring(c, b.k, b.x4, rest, xi, wi, ci, cb);
    }
}

// Stores particle k's corrected point `out` (from x4) and the velocity its move implies
// (core::cpu::strain_limit::strain_vel: v += (out − x)·(1/dt)).
fn store_point(k: u32, x4: vec4<f32>, out: vec4<f32>) {
    pos_out[world_base + k] = out;
    vel[world_base + k] = vec4<f32>(vel[world_base + k].xyz + (out.xyz - x4.xyz) * (1.0 / p.dt), 0.0);
    strained(k, out);
}

// Particle (row, col) of a block: a its point, s0 … s7 its neighbours in slot order
// (core::grid::SLOT_OFFSETS).
fn block_particle(row: u32, col: u32, a: Gp, s0: Gp, s1: Gp, s2: Gp, s3: Gp, s4: Gp, s5: Gp, s6: Gp, s7: Gp) {
    let xi = a.x4.xyz;
    let wi = mobility(a.k, a.x4.w);
    let ci = own_block_count(a, s0, s1, s2, s3, s4, s5, s6, s7);
    var c = Correction(vec3<f32>(0.0), 0.0);
    // A count of 0: none of the particle's springs is over its limit (counted as
    // limit_spring finds each), so none adds anything.
    if ci > 0.0 {
        limit_grid(&c, s0, 0u, xi, wi, ci);
        limit_grid(&c, s1, 1u, xi, wi, ci);
        limit_grid(&c, s2, 2u, xi, wi, ci);
        limit_grid(&c, s3, 3u, xi, wi, ci);
        limit_grid(&c, s4, 4u, xi, wi, ci);
        limit_grid(&c, s5, 5u, xi, wi, ci);
        limit_grid(&c, s6, 6u, xi, wi, ci);
        limit_grid(&c, s7, 7u, xi, wi, ci);
    }
    let out = finish(a.k, a.x4, wi, c);
    if a.inside && interior.enabled != 0u {
        store_point(a.k, a.x4, out);
    }
}

// Particle i from its table (an irregular table).
fn table_particle(i: u32) {
    let x4 = pos[world_base + i];
    let wi = mobility(i, x4.w);
    let ci = own_row_count(i, x4.xyz);
    var c = Correction(vec3<f32>(0.0), 0.0);
    let r = slot_row(i);
    // No spring of a particle whose count is 0 is over its limit (see block_particle).
    let head = select(0u, r.head, ci > 0.0);
    for (var s = 0u; s < head; s++) {
        let slot = row_slot(i, r, s);
        if slot.neighbor >= 0 {
            let b = u32(slot.neighbor);
            let xb4 = pos[world_base + b];
            var cb = 0.0;
            if over(x4.xyz, xb4, slot.rest) != 0.0 {
                cb = row_neighbour_count(b, xb4.xyz);
            }
            limit_spring(&c, b, xb4, slot.rest, x4.xyz, wi, ci, cb);
        }
    }
    let out = finish(i, x4, wi, c);
    store_point(i, x4, out);
}

