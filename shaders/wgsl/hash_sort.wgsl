//! include: state, hash, hash_fn
// hash_sort — per bucket: its range of particle indices sorted (insertion sort; a bucket
// holds a few), so that self_collide sums in one order on every backend.
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let b = flat_id(id, groups);
    if b >= table_size() {
        return;
    }
    let np = num_particles();
    let start = min(cells[4u * b + 1u], np);
    let end = min(start + cells[4u * b], np);
    for (var k = start + 1u; k < end; k++) {
        let v = sorted[4u * k + 1u];
        var m = k;
        loop {
            if m <= start || sorted[4u * (m - 1u) + 1u] <= v {
                break;
            }
            sorted[4u * m + 1u] = sorted[4u * (m - 1u) + 1u];
            m -= 1u;
        }
        sorted[4u * m + 1u] = v;
    }
    // The bounding box of the bucket's grid coordinates, where the cursor and the block
    // total were (core::cpu::self_collide::hash_sort).
    if start == end {
        return;
    }
    let mask = (1u << COORD_BITS) - 1u;
    var lo = vec2<u32>(0xffffffffu);
    var hi = vec2<u32>(0u);
    for (var k = start; k < end; k++) {
        let w = sorted[4u * k + 1u];
        let c = vec2<u32>(w & mask, w >> COORD_BITS);
        lo = min(lo, c);
        hi = max(hi, c);
    }
    cells[4u * b + 2u] = lo.x | (lo.y << COORD_BITS);
    cells[4u * b + 3u] = hi.x | (hi.y << COORD_BITS);
}
