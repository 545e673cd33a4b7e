//! include: table, window, strain_points, strain_window, strain_count_fn, strain_counts_inline, strain_limit_pass, adjacency, strain_fn
//! worlds
// strain_limit_inline — strain_limit with no count dispatch before it
// (`strain_counts=inline`): the pass counts the springs over their limit itself, its own
// from the window it loads and a neighbour's only for a spring over its limit
// (shared/strain_counts_inline.wgsl): the same counts, the same bits
// (core::cpu::strain_limit::count_at, then limit_at). Reads pos, writes pos_out.

// Nothing more per corrected point.
fn strained(k: u32, x4: vec4<f32>) {}
