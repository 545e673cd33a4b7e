// The counts the strain limit's pass divides by, as strain_count.wgsl left them in aux0 for
// these positions (`strain_counts=dispatch`: a count dispatch before each pass).
@group(0) @binding(24) var<storage, read_write> strain_counts: array<vec4<f32>>;

// Grid point a's count (its neighbours s0 … s7 unused here).
fn own_block_count(a: Gp, s0: Gp, s1: Gp, s2: Gp, s3: Gp, s4: Gp, s5: Gp, s6: Gp, s7: Gp) -> f32 {
    return strain_counts[world_base + a.k].x;
}

// Particle i's count (at xi) on an irregular table.
fn own_row_count(i: u32, xi: vec3<f32>) -> f32 {
    return strain_counts[world_base + i].x;
}

// A neighbour's count: grid point b, or particle b (at xb) of an irregular table.
fn grid_neighbour_count(b: Gp) -> f32 {
    return strain_counts[world_base + b.k].x;
}

fn row_neighbour_count(b: u32, xb: vec3<f32>) -> f32 {
    return strain_counts[world_base + b].x;
}
