// The broad phase's cell-to-bucket rule (core::broad), for every contact's grid: a
// cell's bucket is its row's start (the primes of Teschner et al. 2003) plus its x, so
// that the cells of a row in x are consecutive buckets.
const PRIME_Y: i32 = 689287499;
const PRIME_Z: i32 = 283923481;

// core::broad::row_start: 4 ((y mod 4) + 4 (z mod 4)) + 64 hash(y, z), so that no two
// rows around a point share a bucket.
fn row_start(y: i32, z: i32) -> u32 {
    let low = bitcast<u32>((y & 3) + 4 * (z & 3));
    let hash = bitcast<u32>((y * PRIME_Y) ^ (z * PRIME_Z));
    return 4u * low + hash * 64u;
}

// The cell's bucket among size (a power of two): its row's start plus its x.
fn bucket(c: vec3<i32>, size: u32) -> u32 {
    return (row_start(c.y, c.z) + bitcast<u32>(c.x)) & (size - 1u);
}
