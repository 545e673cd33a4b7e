//! include: state, hash, hash_fn, cells
// hash_scan_top — one workgroup: the exclusive prefix of the blocks' totals (totals[4g + 2],
// counted by hash_count) in place, each block's offset (core::cpu::self_collide::
// hash_scan_top). Each invocation sums a run of consecutive totals, one scan over the
// workgroup offsets the runs, and each invocation writes its run's prefixes: two barrier
// rounds, however many blocks.
var<workgroup> wg_count: u32;
var<workgroup> run_sums: array<u32, WORKGROUP>;

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(local_invocation_index) li: u32) {
    p = step_params;
    if li == 0u {
        wg_count = (table_size() + WORKGROUP - 1u) / WORKGROUP;
    }
    let count = workgroupUniformLoad(&wg_count);
    let per = (count + WORKGROUP - 1u) / WORKGROUP;
    let first = min(li * per, count);
    let last = min(first + per, count);
    var sum = 0u;
    for (var g = first; g < last; g++) {
        sum += totals[4u * g + 2u];
    }
    run_sums[li] = sum;
    workgroupBarrier();
    // The runs before this one (WORKGROUP adds from workgroup memory: cheaper on lavapipe
    // than a Hillis-Steele scan's barriers).
    var acc = 0u;
    for (var k = 0u; k < li; k++) {
        acc += run_sums[k];
    }
    for (var g = first; g < last; g++) {
        let total = totals[4u * g + 2u];
        totals[4u * g + 2u] = acc;
        acc += total;
    }
}
