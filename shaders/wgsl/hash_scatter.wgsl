//! include: state, hash_atomic, hash_fn
// hash_scatter — per particle: its grid coordinates (i | j << 12) into the next free slot
// of its bucket's range (atomics: in any order; hash_sort follows).
// core::cpu::self_collide::hash_scatter.
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let b = sorted[4u * i];
    let slot = atomicAdd(&cells[4u * b + 2u], 1u);
    if slot < num_particles() {
        sorted[4u * slot + 1u] = (i % p.n) | ((i / p.n) << COORD_BITS);
    }
}
