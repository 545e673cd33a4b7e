// The per-particle spring table in a sampled image (the thesis's texture memory): one
// rgba32uint texel per slot (neighbour, rest, ks, kd as bits), slot s of particle i at
// texel t = 12 i + s (a mesh's rows one after another: entry s of row r at r.first + s),
// row t / TABLE_WIDTH, column t % TABLE_WIDTH (clothlab_engine::tables::table_texels lays
// it out; TABLE_WIDTH is generated from clothlab_core::layout).

@group(0) @binding(20) var table: texture_2d<u32>;

// Slot s of particle i's row r (shared/adjacency.wgsl's slot_row(i)).
fn row_slot(i: u32, r: Row, s: u32) -> SpringSlot {
    return texel_slot(table_index(r, s));
}

fn slot_at(i: u32, s: u32) -> SpringSlot {
    return texel_slot(i * SLOTS + s);
}

fn texel_slot(t: u32) -> SpringSlot {
    let v = textureLoad(table, vec2<i32>(i32(t % TABLE_WIDTH), i32(t / TABLE_WIDTH)), 0);
    return SpringSlot(bitcast<i32>(v.x), bitcast<f32>(v.y), bitcast<f32>(v.z), bitcast<f32>(v.w));
}
