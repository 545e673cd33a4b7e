//! include: state, tri, cells
//! worlds
// tri_grid_scatter — per primitive: into its bucket's next entry, in any order (the
// bucket's word becomes its end; tri_grid_sort orders each bucket after)
// (core::cpu::tri_contact::tri_grid_scatter).
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
    let slot = atomicAdd(&tri_ints[ib() + grid_at() + bucket_of(b, o, load_f(TRI_AT_CELL))], 1u);
    atomicStore(&tri_ints[ib() + entries_at() + slot], select(o - tris_len(), o, o < tris_len()));
}
