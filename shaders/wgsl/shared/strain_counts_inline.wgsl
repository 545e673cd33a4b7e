// The counts the strain limit's pass divides by, computed by the pass itself
// (`strain_counts=inline`: no count dispatch, no aux0): its own from the neighbours it
// has loaded anyway, a neighbour's — two rings out — only for a spring over its limit, the
// one place the pass uses it (shared/strain_limit_pass.wgsl). The same numbers as
// strain_count.wgsl's (shared/strain_count_fn.wgsl, on the same positions).

fn own_block_count(a: Gp, s0: Gp, s1: Gp, s2: Gp, s3: Gp, s4: Gp, s5: Gp, s6: Gp, s7: Gp) -> f32 {
    return count_block(a, s0, s1, s2, s3, s4, s5, s6, s7);
}

fn own_row_count(i: u32, xi: vec3<f32>) -> f32 {
    return count_row(i, xi);
}

fn grid_neighbour_count(b: Gp) -> f32 {
    return count_grid_point(b);
}

fn row_neighbour_count(b: u32, xb: vec3<f32>) -> f32 {
    return count_row(b, xb);
}
