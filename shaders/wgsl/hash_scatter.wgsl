//! include: state, hash_atomic, hash_fn
// hash_scatter — per particle: its position and slot word (sorted[4i + 3], as the bits of
// w) into the slot before its bucket's end (atomics: in any order), which leaves the
// bucket's word at its start (core::cpu::self_collide::hash_scatter).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let np = num_particles();
    let i = flat_id(id, groups);
    if i >= np {
        return;
    }
    let b = sorted[4u * i];
    if b >= table_size() {
        return;
    }
    let slot = atomicSub(&cells[b], 1u) - 1u;
    if slot < np {
        slot_pos[slot] = vec4<f32>(pos[i].xyz, bitcast<f32>(sorted[4u * i + 3u]));
    }
}
