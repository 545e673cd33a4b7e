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
}
