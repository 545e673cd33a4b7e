// The strain limit's points (the pass, shared/strain_limit_pass.wgsl, and the count,
// strain_count.wgsl): the step constants, the positions and the spring table's interior,
// and a grid point with its particle. The entry point comes from shared/strain_window.wgsl
// (a block's window of 18 grid points an invocation) or shared/strain_strip.wgsl (a
// block's columns down a strip of rows). Each including file defines
// `block_particle(row, col, a, s0 … s7)` (a grid point and its neighbours in slot order)
// and `table_particle(i)` (a particle from its table); the counts of over-stretched
// springs (core::cpu::strain_limit) come from shared/strain_count_fn.wgsl and
// shared/strain_counts_aux.wgsl or shared/strain_counts_inline.wgsl.
@group(0) @binding(0) var<uniform> step_params: StepParams;
// Copied from step_params by the kernel's first statement (see shared/state.wgsl).
var<private> p: StepParams;
@group(0) @binding(1) var<storage, read_write> pos: array<vec4<f32>>;
@group(0) @binding(16) var<uniform> interior_slots: GridSpringConstants;
var<private> interior: GridSpringConstants;

// The pins' positions for the tethers (shared/strain_fn.wgsl's `finish`): this pass's
// input positions.
fn pin_point(pin: u32) -> vec3<f32> {
    return pos[world_base + pin].xyz;
}

// Grid point (c, r): its particle (particle 0 when outside the grid, so that every lane
// loads something), that particle's pos, and whether it is inside.
struct Gp {
    k: u32,
    x4: vec4<f32>,
    inside: bool,
}

fn grid_point(c: i32, r: i32) -> Gp {
    let n = i32(p.n);
    let inside = c >= 0 && c < n && r >= 0 && r < n;
    let k = u32(select(0, r * n + c, inside));
    return Gp(k, pos[world_base + k], inside);
}
