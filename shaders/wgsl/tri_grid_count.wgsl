//! include: state, tri, cells
//! worlds
// tri_grid_count — per primitive (triangles, then edges): one more in its bucket's count,
// its box's extent into its grid's largest, a wide box's not (it is listed apart)
// (core::cpu::tri_contact::tri_grid_count).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let o = flat_id(id, groups);
    if o >= tris_len() + edges_len() {
        return;
    }
    let b = prim_box(o);
    if !(finite3(b.lo) && finite3(b.hi)) {
        return;
    }
    let cell = load_f(TRI_AT_CELL);
    atomicAdd(&tri_ints[ib() + grid_at() + bucket_of(b, o, cell)], 1u);
    if is_big(b, cell) {
        return;
    }
    let ext = select(TRI_AT_EXTENT_E, TRI_AT_EXTENT_T, o < tris_len());
    let e = b.hi - b.lo;
    atomicMax(&tri_ints[ib() + ext], bitcast<u32>(e.x));
    atomicMax(&tri_ints[ib() + ext + 1u], bitcast<u32>(e.y));
    atomicMax(&tri_ints[ib() + ext + 2u], bitcast<u32>(e.z));
}
