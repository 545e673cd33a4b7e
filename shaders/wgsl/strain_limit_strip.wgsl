//! include: table, strain_points, strain_count_fn, strain_counts_inline, strain_limit_pass, adjacency, strain_fn, strain_strip
//! worlds
// strain_limit_strip — strain_limit with no count dispatch before it, down strips of rows
// (`strain_counts=strip`, shared/strain_strip.wgsl): each spring's length computed once
// for the counts of both its ends and the pass; the same counts, the same bits
// (core::cpu::strain_limit::count_at, then limit_at). Reads pos, writes pos_out.

// Nothing more per corrected point.
fn strained(k: u32, x4: vec4<f32>) {}
