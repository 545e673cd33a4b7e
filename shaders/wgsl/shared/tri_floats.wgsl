// The contact between triangles: each particle's position at the substep's start and
// its bound (w), read and written plainly (shared/tri_bounds.wgsl: the bounds' atomics).
@group(0) @binding(39) var<storage, read_write> tri_floats: array<vec4<f32>>;
