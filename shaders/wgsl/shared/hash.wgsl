// Self-collision's hash (core::cpu::self_collide), in integrator scratch buffers that are
// dead by then: aux2 one u32 word per bucket (count, then end, then start of its range),
// aux3 the blocks' totals (u32 word 2 of the first blocks), aux4 per slot the position of
// the particle there with its slot word as the bits of w.
@group(0) @binding(26) var<storage, read_write> cells: array<u32>;
@group(0) @binding(27) var<storage, read_write> totals: array<u32>;
@group(0) @binding(28) var<storage, read_write> slot_pos: array<vec4<f32>>;
