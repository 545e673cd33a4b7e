// Where each particle's row of the spring table and of the face slots lies
// (clothlab_core::tables::Rows). A grid's rows are fixed (SLOTS slots, the first
// STRAIN_SLOTS held by the strain limit; FACE_SLOTS faces) and computed here; a mesh's are
// compressed rows of any length, read from `adjacency` (clothlab_core::layout::Buf::
// Adjacency): per particle and one past the last, (first slot, end of the head, first
// face slot, 0). The branch is on the step constants (n = 0 on a mesh): uniform.

@group(0) @binding(30) var<storage, read> adjacency: array<vec4<u32>>;

// A row: its first entry in the flat table, its length, and how many of its first
// entries the strain limit holds (a mesh's edges).
struct Row {
    first: u32,
    count: u32,
    head: u32,
}

fn slot_row(i: u32) -> Row {
    if p.n == 0u {
        let a = adjacency[i];
        let end = adjacency[i + 1u].x;
        return Row(a.x, end - a.x, a.y - a.x);
    }
    return Row(i * SLOTS, SLOTS, STRAIN_SLOTS);
}

fn face_row(i: u32) -> Row {
    if p.n == 0u {
        let first = adjacency[i].z;
        let end = adjacency[i + 1u].z;
        return Row(first, end - first, end - first);
    }
    return Row(i * FACE_SLOTS, FACE_SLOTS, FACE_SLOTS);
}
