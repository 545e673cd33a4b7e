//! include: table, window, strain_window, adjacency, strain_fn
// strain_count — every particle's count of strain-limited springs over (1 + τ)·rest
// (core::cpu::strain_limit::count_at), into aux0.x: what the pass after it divides each
// spring by the larger of its two ends' counts of. The same blocks, window and table
// modes as strain_limit (shared/strain_window.wgsl); a spring is over the limit exactly
// when the pass finds it so (the same length, the same comparison).

fn over_grid(b: Gp, s: u32, xi: vec3<f32>) -> f32 {
    return select(0.0, over(xi, b.x4, interior.slots[s].rest), b.inside);
}

// Particle (row, col) of a block: a its point, s0 … s7 its neighbours in slot order.
fn block_particle(row: u32, col: u32, a: Gp, s0: Gp, s1: Gp, s2: Gp, s3: Gp, s4: Gp, s5: Gp, s6: Gp, s7: Gp) {
    let xi = a.x4.xyz;
    var c = over_grid(s0, 0u, xi);
    c += over_grid(s1, 1u, xi);
    c += over_grid(s2, 2u, xi);
    c += over_grid(s3, 3u, xi);
    c += over_grid(s4, 4u, xi);
    c += over_grid(s5, 5u, xi);
    c += over_grid(s6, 6u, xi);
    c += over_grid(s7, 7u, xi);
    if a.inside && interior.enabled != 0u {
        strain_counts[a.k] = vec4<f32>(c, 0.0, 0.0, 0.0);
    }
}

// Particle i from its table (an irregular table).
fn table_particle(i: u32) {
    let xi = pos[i].xyz;
    var c = 0.0;
    let r = slot_row(i);
    for (var s = 0u; s < r.head; s++) {
        let slot = row_slot(i, r, s);
        if slot.neighbor >= 0 {
            c += over(xi, pos[u32(slot.neighbor)], slot.rest);
        }
    }
    strain_counts[i] = vec4<f32>(c, 0.0, 0.0, 0.0);
}
