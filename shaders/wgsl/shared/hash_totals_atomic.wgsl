// The blocks' totals of the hash (see shared/hash.wgsl) for the count's atomics.
@group(0) @binding(27) var<storage, read_write> block_totals: array<atomic<u32>>;
