// The per-particle spring table in storage buffers, in two bindings so that each stays
// within the 128 MiB a storage binding may span on many adapters up to n = 1024:
// slots 0..8 (structural and shear) and slots 8..12 (bend). The build also emits every
// kernel that includes this file as `<kernel>_tex`, reading the table from a sampled
// image instead (shared/table_tex.wgsl).

@group(0) @binding(6) var<storage, read> slots: array<SpringSlot>;
@group(0) @binding(14) var<storage, read> bend_slots: array<SpringSlot>;

// Slot s of particle i's row r (shared/adjacency.wgsl's slot_row(i)): a mesh's rows lie
// one after another, the first half of them in the first binding, the rest in the second.
fn row_slot(i: u32, r: Row, s: u32) -> SpringSlot {
    if p.n == 0u {
        if r.second {
            return bend_slots[r.first + s];
        }
        return slots[r.first + s];
    }
    return slot_at(i, s);
}

fn slot_at(i: u32, s: u32) -> SpringSlot {
    if s < STRAIN_SLOTS {
        return slots[i * STRAIN_SLOTS + s];
    }
    return bend_slots[i * (SLOTS - STRAIN_SLOTS) + s - STRAIN_SLOTS];
}
