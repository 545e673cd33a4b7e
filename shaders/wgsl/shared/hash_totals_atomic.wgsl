// The blocks' totals of the hash (see shared/hash.wgsl) for the count's atomics.
@group(0) @binding(27) var<storage, read_write> block_totals: array<atomic<u32>>;

// One more particle at x in its bucket's count and in its block's total (hash_count,
// strain_limit_count; with shared/hash_atomic.wgsl and shared/hash_fn.wgsl).
// (A batch's world counts into its own table: table_base.)
fn count_point(x: vec3<f32>) {
    let b = table_base() + bucket(cell_of(x), table_size());
    atomicAdd(&cells[b], 1u);
    atomicAdd(&block_totals[4u * (b / WORKGROUP) + 2u], 1u);
}
