// Self-collision's hash (core::cpu::self_collide), in integrator scratch buffers that are
// dead by then, as u32 words: aux2 one word per bucket (count, then end, then start of its
// range), aux3 per particle [bucket of particle i, particle at slot i, block total, -].
@group(0) @binding(26) var<storage, read_write> cells: array<u32>;
@group(0) @binding(27) var<storage, read_write> sorted: array<u32>;
