//! include: table, window, strain_points, strain_window, strain_counts_aux, strain_count_fn, adjacency, strain_fn
//! worlds
// strain_count — every particle's count of strain-limited springs over (1 + τ)·rest
// (core::cpu::strain_limit::count_at), into aux0.x: what the pass after it divides each
// spring by the larger of its two ends' counts of. The same blocks, window and table
// modes as strain_limit (shared/strain_window.wgsl); a spring is over the limit exactly
// when the pass finds it so (the same length, the same comparison).

// Particle (row, col) of a block: a its point, s0 … s7 its neighbours in slot order.
fn block_particle(row: u32, col: u32, a: Gp, s0: Gp, s1: Gp, s2: Gp, s3: Gp, s4: Gp, s5: Gp, s6: Gp, s7: Gp) {
    let c = count_block(a, s0, s1, s2, s3, s4, s5, s6, s7);
    if a.inside && interior.enabled != 0u {
        strain_counts[world_base + a.k] = vec4<f32>(c, 0.0, 0.0, 0.0);
    }
}

// Particle i from its table (an irregular table).
fn table_particle(i: u32) {
    strain_counts[world_base + i] = vec4<f32>(count_row(i, pos[world_base + i].xyz), 0.0, 0.0, 0.0);
}
