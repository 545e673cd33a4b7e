//! include: state, hash_atomic, hash_fn
// hash_count — per particle: its bucket into sorted[4i], its slot word into sorted[4i + 3],
// one more in its bucket's count
// (core::cpu::self_collide::hash_count; the recipe clears the counts before).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let x = pos[i];
    let c = cell_of(x.xyz);
    let b = bucket(c, table_size());
    sorted[4u * i] = b;
    let pinned = select(0u, PINNED, x.w == 0.0);
    sorted[4u * i + 3u] = (i % p.n) | ((i / p.n) << COORD_BITS) | (row_tag(c.y, c.z) << (2u * COORD_BITS)) | pinned;
    atomicAdd(&cells[b], 1u);
}
