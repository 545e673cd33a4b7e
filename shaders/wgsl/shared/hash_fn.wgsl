// The hash of core::cpu::self_collide: cells are cubes of side 2 self_thickness (the
// point times 1/(2t), computed on the host: a product rounds alike everywhere, a quotient
// does not), buckets a power of two, the primes of Teschner et al. 2003.
const CELL_LIMIT: f32 = 1e9;
const PRIME_X: i32 = 92837111;
const PRIME_Y: i32 = 689287499;
const PRIME_Z: i32 = 283923481;

fn cell_of(x: vec3<f32>) -> vec3<i32> {
    return vec3<i32>(clamp(floor(x * p.inv_cell), vec3<f32>(-CELL_LIMIT), vec3<f32>(CELL_LIMIT)));
}

// The largest power of two not above n².
fn table_size() -> u32 {
    return 1u << firstLeadingBit(max(num_particles(), 1u));
}

// The cell's bucket among size (a power of two).
fn bucket(c: vec3<i32>, size: u32) -> u32 {
    return bitcast<u32>((c.x * PRIME_X) ^ (c.y * PRIME_Y) ^ (c.z * PRIME_Z)) & (size - 1u);
}

// What a slot holds for particle i: its grid coordinates i | j << 12
// (core::cpu::self_collide::slot_word).
const COORD_BITS: u32 = 12u;

// Inclusive prefix sum of v over the workgroup (Hillis-Steele through workgroup memory).
// Every invocation must call it (barriers inside); scan_acc[WORKGROUP - 1] is the total.
var<workgroup> scan_acc: array<u32, WORKGROUP>;

fn workgroup_scan(v: u32, li: u32) -> u32 {
    scan_acc[li] = v;
    workgroupBarrier();
    for (var s = 1u; s < WORKGROUP; s <<= 1u) {
        var add = 0u;
        if li >= s {
            add = scan_acc[li - s];
        }
        workgroupBarrier();
        scan_acc[li] += add;
        workgroupBarrier();
    }
    return scan_acc[li];
}
