// The contact between triangles' start and bounds as words: word 4k + 3 is vertex k's
// bound, lowered by atomic minima of its bits (non-negative floats order as their bits).
@group(0) @binding(39) var<storage, read_write> tri_bounds: array<atomic<u32>>;
