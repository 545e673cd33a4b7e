// A particle's count of strain-limited springs over (1 + τ)·rest
// (core::cpu::strain_limit::count_at), from the positions the strain limit's pass reads:
// what strain_count.wgsl stores in aux0 for the pass after it, and what a pass that counts
// for itself (`strain_counts=inline`: shared/strain_counts_inline.wgsl) computes where it
// needs a count. The same lengths and comparison as the pass (`over`, shared/strain_fn.wgsl).

fn over_grid(b: Gp, s: u32, xi: vec3<f32>) -> f32 {
    return select(0.0, over(xi, b.x4, interior.slots[s].rest), b.inside);
}

// Grid point a's count, s0 … s7 its neighbours in slot order (core::grid::SLOT_OFFSETS).
fn count_block(a: Gp, s0: Gp, s1: Gp, s2: Gp, s3: Gp, s4: Gp, s5: Gp, s6: Gp, s7: Gp) -> f32 {
    let xi = a.x4.xyz;
    var c = over_grid(s0, 0u, xi);
    c += over_grid(s1, 1u, xi);
    c += over_grid(s2, 2u, xi);
    c += over_grid(s3, 3u, xi);
    c += over_grid(s4, 4u, xi);
    c += over_grid(s5, 5u, xi);
    c += over_grid(s6, 6u, xi);
    c += over_grid(s7, 7u, xi);
    return c;
}

// Grid point b's count, its eight neighbours loaded: slots (-1,0) (1,0) (0,-1) (0,1)
// (-1,-1) (1,-1) (-1,1) (1,1) as (column, row) offsets.
fn count_grid_point(b: Gp) -> f32 {
    let c = i32(b.k % p.n);
    let r = i32(b.k / p.n);
    return count_block(
        b,
        grid_point(c - 1, r),
        grid_point(c + 1, r),
        grid_point(c, r - 1),
        grid_point(c, r + 1),
        grid_point(c - 1, r - 1),
        grid_point(c + 1, r - 1),
        grid_point(c - 1, r + 1),
        grid_point(c + 1, r + 1)
    );
}

// Particle i's count (at xi) from its table (an irregular table).
fn count_row(i: u32, xi: vec3<f32>) -> f32 {
    var c = 0.0;
    let r = slot_row(i);
    for (var s = 0u; s < r.head; s++) {
        let slot = row_slot(i, r, s);
        if slot.neighbor >= 0 {
            c += over(xi, pos[world_base + u32(slot.neighbor)], slot.rest);
        }
    }
    return c;
}
