// The hash's buffers (see shared/hash.wgsl) for the kernels that count and place with
// atomics.
@group(0) @binding(26) var<storage, read_write> cells: array<atomic<u32>>;
@group(0) @binding(28) var<storage, read_write> slot_pos: array<vec4<f32>>;
