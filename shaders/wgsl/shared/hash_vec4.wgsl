// The hash's bucket words (see shared/hash.wgsl) four at a time, for the prefix sum's
// kernel (hash_scan_blocks): one read site of four components instead of four of one (on
// lavapipe each site walks its 8 lanes, a mask test per lane).
@group(0) @binding(26) var<storage, read_write> cells4: array<vec4<u32>>;
@group(0) @binding(27) var<storage, read_write> totals: array<u32>;
