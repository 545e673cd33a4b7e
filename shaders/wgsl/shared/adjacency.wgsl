// Where each particle's row of the spring table and of the face slots lies
// (clothlab_core::tables::Rows). A grid's rows are fixed (SLOTS slots, the first
// STRAIN_SLOTS held by the strain limit; FACE_SLOTS faces) and computed here; a mesh's are
// compressed rows of any length, read from `adjacency` (clothlab_core::layout::Buf::
// Adjacency, clothlab_engine::tables::adjacency): per particle (first slot within the
// binding that holds the row, head length, first face slot, slot count | BINDING_2 where
// the row is in the table's second binding), and one past the last (0, 0, end of the
// faces, the second binding's first entry in the whole table). The branch is on the step
// constants (n = 0 on a mesh): uniform.

@group(0) @binding(30) var<storage, read> adjacency: array<vec4<u32>>;

const BINDING_2: u32 = 0x80000000u;

// A row: its first entry (in the binding `second` names), its length, and how many of its
// first entries the strain limit holds (a mesh's edges).
struct Row {
    first: u32,
    count: u32,
    head: u32,
    second: bool,
}

fn slot_row(i: u32) -> Row {
    if p.n == 0u {
        let a = adjacency[i];
        return Row(a.x, a.w & ~BINDING_2, a.y, (a.w & BINDING_2) != 0u);
    }
    return Row(i * SLOTS, SLOTS, STRAIN_SLOTS, false);
}

fn face_row(i: u32) -> Row {
    if p.n == 0u {
        let first = adjacency[i].z;
        let end = adjacency[i + 1u].z;
        return Row(first, end - first, end - first, false);
    }
    return Row(i * FACE_SLOTS, FACE_SLOTS, FACE_SLOTS, false);
}

// The whole table's index of entry s of row r (the image holds the two bindings' entries
// one after the other).
fn table_index(r: Row, s: u32) -> u32 {
    if r.second {
        return adjacency[p.num_particles].w + r.first + s;
    }
    return r.first + s;
}
