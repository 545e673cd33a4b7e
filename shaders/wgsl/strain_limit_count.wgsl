//! include: table, window, strain_points, strain_window, strain_counts_aux, strain_limit_pass, hash_atomic, hash_totals_atomic, hash_fn, adjacency, strain_fn, cells
//! worlds
// strain_limit_count — the strain limit's last pass (shared/strain_limit_pass.wgsl), each
// corrected point then counted into the self-collision hash as hash_count counts it
// (core::cpu::strain_limit::limit_at, then core::cpu::self_collide::hash_count on the
// pass's output; the recipe clears the counts before): one dispatch and one read of the
// positions fewer when self-collision follows a strain limit (a dispatch costs lavapipe
// about 50 µs).

fn strained(k: u32, x4: vec4<f32>) {
    count_point(x4.xyz);
}
