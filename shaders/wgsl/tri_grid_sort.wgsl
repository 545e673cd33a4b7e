//! include: state, tri, cells
//! worlds
// tri_grid_sort — per bucket (both grids'): its entries in increasing order, by insertion
// (a bucket holds a few), so that every query meets them in one order
// (core::cpu::tri_contact::tri_grid_sort).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let k = flat_id(id, groups);
    if k >= 2u * (buckets() + 1u) {
        return;
    }
    let start = bucket_start(k);
    let end = bucket_end(k);
    for (var i = start + 1u; i < end; i++) {
        let v = atomicLoad(&tri_ints[ib() + i]);
        var j = i;
        while j > start && atomicLoad(&tri_ints[ib() + j - 1u]) > v {
            atomicStore(&tri_ints[ib() + j], atomicLoad(&tri_ints[ib() + j - 1u]));
            j -= 1u;
        }
        atomicStore(&tri_ints[ib() + j], v);
    }
}
