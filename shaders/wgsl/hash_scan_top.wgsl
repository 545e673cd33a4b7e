//! include: state, hash, hash_fn, cells
//! worlds
// hash_scan_top — one workgroup: the exclusive prefix of the blocks' totals (totals[4g + 2],
// counted by hash_count) in place, each block's offset (core::cpu::self_collide::
// hash_scan_top). Each invocation sums a run of consecutive totals, one scan over the
// workgroup offsets the runs, and each invocation writes its run's prefixes: two barrier
// rounds, however many blocks.
// A batch's world (one workgroup each) scans its own blocks from its first slot,
// world_base: each world's table holds its np particles.
var<workgroup> wg_count: u32;
var<workgroup> run_sums: array<u32, WORKGROUP>;

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(local_invocation_index) li: u32, @builtin(global_invocation_id) id: vec3<u32>) {
    p = step_params;
    if li == 0u {
        wg_count = hash_blocks();
    }
    let count = workgroupUniformLoad(&wg_count);
    let per = (count + WORKGROUP - 1u) / WORKGROUP;
    let first = min(li * per, count);
    let last = min(first + per, count);
    var sum = 0u;
    let blocks = block_base();
    for (var g = first; g < last; g++) {
        sum += totals[4u * (blocks + g) + 2u];
    }
    run_sums[li] = sum;
    workgroupBarrier();
    // The runs before this one (WORKGROUP adds from workgroup memory: cheaper on lavapipe
    // than a Hillis-Steele scan's barriers).
    var acc = world_base;
    for (var k = 0u; k < li; k++) {
        acc += run_sums[k];
    }
    for (var g = first; g < last; g++) {
        let total = totals[4u * (blocks + g) + 2u];
        totals[4u * (blocks + g) + 2u] = acc;
        acc += total;
    }
}
