//! include: state, hash, hash_fn
// hash_scan_top — one workgroup: the exclusive prefix of the workgroups' totals
// (cells[g].w), WORKGROUP of them at a time with the running total carried.
var<workgroup> wg_count: u32;

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(local_invocation_index) li: u32) {
    p = step_params;
    if li == 0u {
        wg_count = (table_size() + WORKGROUP - 1u) / WORKGROUP;
    }
    let count = workgroupUniformLoad(&wg_count);
    var carry = 0u;
    for (var base = 0u; base < count; base += WORKGROUP) {
        let g = base + li;
        var c = 0u;
        if g < count {
            c = cells[4u * g + 3u];
        }
        let incl = workgroup_scan(c, li);
        if g < count {
            cells[4u * g + 3u] = carry + incl - c;
        }
        carry += scan_acc[WORKGROUP - 1u];
        workgroupBarrier();
    }
}
