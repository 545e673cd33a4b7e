//! include: table, window, strain_points, strain_window, strain_count_fn, strain_counts_inline, strain_limit_pass, hash_atomic, hash_totals_atomic, hash_fn, adjacency, strain_fn, cells
//! worlds
// strain_limit_inline_count — strain_limit_count counting its own springs over their limit
// (`strain_counts=inline`, shared/strain_counts_inline.wgsl): the strain limit's last pass,
// each corrected point then counted into the self-collision hash (core::cpu::strain_limit
// ::count_at and limit_at, then core::cpu::self_collide::hash_count on the pass's output).

fn strained(k: u32, x4: vec4<f32>) {
    count_point(x4.xyz);
}
