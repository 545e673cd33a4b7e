//! include: state, hash_atomic, hash_fn, hash_vel, cells
//! worlds
// hash_scatter — per particle: its position and slot word (as the bits of w; its bucket and
// word computed again from its position) into the slot before its bucket's end (atomics:
// in any order), which leaves the bucket's word at its start
// (core::cpu::self_collide::hash_scatter); with Coulomb friction its velocity into
// vel_copy (by index).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let np = num_particles();
    let i = flat_id(id, groups);
    if i >= np {
        return;
    }
    if coulomb() {
        vel_copy[world_base + i] = vel[world_base + i];
    }
    let x = pos[world_base + i];
    let c = cell_of(x.xyz);
    // (A batch's world: its own table, its slots from world_base.)
    let slot = atomicSub(&cells[table_base() + bucket(c, table_size())], 1u) - 1u;
    if slot - world_base < np {
        let pinned = select(0u, PINNED, x.w == 0.0);
        let word = slot_id(i) | (row_tag(c.y, c.z) << (2u * COORD_BITS)) | pinned;
        slot_pos[slot] = vec4<f32>(x.xyz, bitcast<f32>(word));
    }
}
