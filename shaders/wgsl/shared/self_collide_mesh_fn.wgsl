// A mesh's side of the self-collision response (self_collide_mesh,
// self_collide_mesh_friction): which particles of a mesh may push each other.

// The spring table (shared/table.wgsl's bindings, read directly: a mesh's rows lie one
// after another, the first half in the first, the rest in the second).
@group(0) @binding(6) var<storage, read> strain_table: array<SpringSlot>;
@group(0) @binding(14) var<storage, read> bend_table: array<SpringSlot>;

// Whether b is not among a's springs (the rest distance is checked for the whole mesh
// when the parameters are).
fn mesh_candidates(a: u32, b: u32) -> bool {
    var spring = a == b;
    let r = slot_row(a);
    for (var s = 0u; s < r.count; s++) {
        var slot: SpringSlot;
        if r.second {
            slot = bend_table[r.first + s];
        } else {
            slot = strain_table[r.first + s];
        }
        spring = spring || slot_other(slot) == i32(b);
    }
    return !spring;
}

// The pos.w of the particle whose slot word is w: 0 pinned, else its own (a mesh's masses
// differ), read for a contact only.
fn other_mobility(w: u32, hit: bool) -> f32 {
    var wj = 0.0;
    if hit && (w & PINNED) == 0u {
        wj = pos[world_base + (w & INDEX_MASK)].w;
    }
    return wj;
}

// A mesh's contact: close, and not one of m's springs.
fn contact(m: Mover, w: u32, close: bool) -> bool {
    if !close {
        return false;
    }
    return mesh_candidates(m.i, w & INDEX_MASK);
}
