// The hash of core::cpu::self_collide: cells are cubes of side self_thickness (the point
// times 1/t, computed on the host: a product rounds alike everywhere, a quotient does
// not), buckets a power of two, a cell's bucket by the broad phase's rule (cells.wgsl).
const CELL_LIMIT: f32 = 1e9;
// core::cpu::self_collide::TABLE_FACTOR.
const TABLE_FACTOR: u32 = 4u;

// A point in cell units, clamped.
fn scaled(x: vec3<f32>) -> vec3<f32> {
    return clamp(x * p.inv_cell, vec3<f32>(-CELL_LIMIT), vec3<f32>(CELL_LIMIT));
}

fn cell_of(x: vec3<f32>) -> vec3<i32> {
    return vec3<i32>(floor(scaled(x)));
}

// TABLE_FACTOR times the largest power of two not above n².
fn table_size() -> u32 {
    return TABLE_FACTOR << firstLeadingBit(max(p.num_particles, 1u));
}

// The blocks of WORKGROUP buckets the scan sums separately
// (core::cpu::self_collide::hash_blocks).
fn hash_blocks() -> u32 {
    return (table_size() + WORKGROUP - 1u) / WORKGROUP;
}

// A batch of worlds (a kernel's `_w` twin) lays the worlds' tables one after another, each
// a whole number of blocks: the world's first bucket and first block (0 in a single run).
fn table_base() -> u32 {
    return world_index * hash_blocks() * WORKGROUP;
}

fn block_base() -> u32 {
    return world_index * hash_blocks();
}

// What a slot holds for particle i in cell c besides its position: its grid coordinates,
// its row's tag and whether it is pinned, i | j << 12 | tag << 24 | pinned << 31; on a
// mesh (n = 0) the particle's index in the low 24 bits (core::cpu::self_collide::slot_word,
// row_tag).
const COORD_BITS: u32 = 12u;
const COORD_MASK: u32 = 4095u;
const INDEX_MASK: u32 = 0xffffffu;
const PINNED: u32 = 0x80000000u;

// The low 24 bits of particle i's slot word: a grid's coordinates, a mesh's index.
fn slot_id(i: u32) -> u32 {
    let n = max(p.n, 1u);
    return select((i % n) | ((i / n) << COORD_BITS), i & INDEX_MASK, p.n == 0u);
}

// The index of the particle whose slot word is w (core::cpu::self_collide::slot_particle):
// a grid's j n + i, a mesh's from the low bits.
fn slot_particle(w: u32) -> u32 {
    let n = max(p.n, 1u);
    return select((w & COORD_MASK) + ((w >> COORD_BITS) & COORD_MASK) * n, w & INDEX_MASK, p.n == 0u);
}

fn row_tag(y: i32, z: i32) -> u32 {
    return bitcast<u32>((y & 7) | ((z & 15) << 3u));
}
