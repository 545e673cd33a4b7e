//! include: state, tri, cells
//! worlds
// tri_grid_scan — one workgroup: both grids' bucket counts to their exclusive prefix, each
// bucket's start among the entries (core::cpu::tri_contact::tri_grid_scan). Each
// invocation sums a run of consecutive counts, the runs before it offset it, and it writes
// its run's prefixes (hash_scan_top's pattern).
var<workgroup> run_sums: array<u32, WORKGROUP>;

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(local_invocation_index) li: u32, @builtin(global_invocation_id) id: vec3<u32>) {
    p = step_params;
    let count = 2u * (buckets() + 1u);
    let per = (count + WORKGROUP - 1u) / WORKGROUP;
    let first = min(li * per, count);
    let last = min(first + per, count);
    let g = grid_at();
    var sum = 0u;
    for (var k = first; k < last; k++) {
        sum += atomicLoad(&tri_ints[ib() + g + k]);
    }
    run_sums[li] = sum;
    workgroupBarrier();
    var acc = 0u;
    for (var k = 0u; k < li; k++) {
        acc += run_sums[k];
    }
    for (var k = first; k < last; k++) {
        let n = atomicLoad(&tri_ints[ib() + g + k]);
        atomicStore(&tri_ints[ib() + g + k], acc);
        acc += n;
    }
}
