//! include: state, hash, hash_fn, self_collide_walk
// self_collide_mesh — self_collide on a mesh (shared/self_collide_walk.wgsl): pairs of
// consecutive particles of the list, and a particle's neighbours are its springs, read
// from the table for the few entries within the thickness (core::cpu::self_collide::
// mesh_candidates). A kernel of its own so that a grid's response carries no table loop:
// on lavapipe a branch costs its body whether a lane takes it or not (2.4x the grid's
// response with the loop behind an `if`).

// The spring table (shared/table.wgsl's bindings, read directly).
@group(0) @binding(6) var<storage, read> strain_table: array<SpringSlot>;
@group(0) @binding(14) var<storage, read> bend_table: array<SpringSlot>;

// Whether b is not among a's springs (the rest distance is checked for the whole mesh
// when the parameters are).
fn mesh_candidates(a: u32, b: u32) -> bool {
    var spring = a == b;
    for (var s = 0u; s < STRAIN_SLOTS; s++) {
        spring = spring || slot_other(strain_table[a * STRAIN_SLOTS + s]) == i32(b);
    }
    for (var s = 0u; s < SLOTS - STRAIN_SLOTS; s++) {
        spring = spring || slot_other(bend_table[a * (SLOTS - STRAIN_SLOTS) + s]) == i32(b);
    }
    return !spring;
}

// A mesh's contact: close, and not one of m's springs.
fn contact(m: Mover, w: u32, close: bool) -> bool {
    if !close {
        return false;
    }
    return mesh_candidates(m.i, w & INDEX_MASK);
}
