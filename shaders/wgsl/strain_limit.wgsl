//! include: table, window, strain_points, strain_window, strain_counts_aux, strain_limit_pass, adjacency, strain_fn
//! worlds
// strain_limit — one Jacobi pass of Provot's strain limit plus the tethers
// (core::cpu::strain_limit::limit_at), each spring divided by the larger of its two ends'
// counts that strain_count left in aux0 (the momentum stays). Reads pos, writes pos_out.
// Four consecutive
// particles of a row (BLOCK) per invocation share one window of 18 points (rows j - 1 …
// j + 1); on a regular grid (interior.enabled) neighbours come from offsets and rest
// lengths from the uniform block, with no branches around loads (see shared/gather.wgsl);
// otherwise each particle walks its table.

// Nothing more per corrected point.
fn strained(k: u32, x4: vec4<f32>) {}
