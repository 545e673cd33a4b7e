//! include: state, tri, tri_bounds, cells
//! worlds
// tri_pairs — per owner (the vertices, then the edges): its pairs closer than the reach
// through the grid of the other primitives' boxes, the TRI_SLOTS nearest kept (by
// distance, then index: the same set in any order of the query) and all counted; every
// vertex of a pair has its bound lowered to the fraction of the pair's distance
// (core::cpu::tri_contact::tri_pairs, whose query is core::broad::query: the cells from
// the box's corner less the grid's largest extent to its other corner, each entry whose
// own lowest corner lies in the cell visited, then the wide boxes).
fn lower(k: u32, d: f32) {
    atomicMin(&tri_bounds[4u * world_base + 4u * k + 3u], bitcast<u32>(TRI_BOUND_FRACTION * d));
}

// Whether a pair `d` away with `other` lies after one `e` away with `f` in the order of
// nearness (distance, then index: no two of an owner's pairs tie).
fn farther(d: f32, other: u32, e: f32, f: u32) -> bool {
    return d > e || (d == e && other > f);
}

// Owner o's n-th pair found within its first TRI_SLOTS: `other`, `d` away (the kept
// pairs' distances in the buffer's second half, f32 bits).
fn keep(o: u32, n: u32, other: u32, d: f32) {
    tri_pairs[pb() + o * TRI_SLOTS + n] = other;
    tri_pairs[pb() + (num_owners() + o) * TRI_SLOTS + n] = bitcast<u32>(d);
}

// A later pair of owner o, `other` `d` away: in place of the farthest kept if nearer.
fn replace(o: u32, other: u32, d: f32) {
    let base = o * TRI_SLOTS;
    let dist = num_owners() * TRI_SLOTS + base;
    var far = 0u;
    var far_d = bitcast<f32>(tri_pairs[pb() + dist]);
    for (var k = 1u; k < TRI_SLOTS; k++) {
        let dk = bitcast<f32>(tri_pairs[pb() + dist + k]);
        if farther(dk, tri_pairs[pb() + base + k], far_d, tri_pairs[pb() + base + far]) {
            far = k;
            far_d = dk;
        }
    }
    if farther(far_d, tri_pairs[pb() + base + far], d, other) {
        keep(o, far, other, d);
    }
}

// Owner o's walk over the grid: every pair closer than the reach counted; on the first
// walk (`again` false) the bounds lowered and the first TRI_SLOTS kept, on the second
// (only for an owner with more) every later one offered to `replace`. Two walks because a
// lane of a CPU driver's SIMD runs every branch of the loop masked: the replacement's
// scan in the one walk made the kernel 3 times slower with no owner over its slots.
fn walk(o: u32, again: bool) -> u32 {
    let np = num_particles();
    let vertex = o < np;
    let reach = load_f(TRI_AT_REACH);
    let cell = load_f(TRI_AT_CELL);
    let inv = 1.0 / cell;
    var lo: vec3<f32>;
    var hi: vec3<f32>;
    var first = 0u;
    var own = vec2<u32>(o, o);
    var ext_at = TRI_AT_EXTENT_T;
    var grid = 0u;
    var offset = 0u;
    if vertex {
        lo = at3(o);
        hi = lo;
    } else {
        own = edge_at(o - np);
        let p0 = at3(own.x);
        let p1 = at3(own.y);
        lo = min(p0, p1);
        hi = max(p0, p1);
        first = o - np + 1u;
        ext_at = TRI_AT_EXTENT_E;
        grid = buckets() + 1u;
        offset = tris_len();
    }
    var found = 0u;
    if finite3(lo) && finite3(hi) {
        let extent = vec3<f32>(load_f(ext_at), load_f(ext_at + 1u), load_f(ext_at + 2u));
        let g = vec3<f32>(reach);
        let m = max(abs(lo), abs(hi));
        let slack = vec3<f32>(1e-4 * cell + 1e-6 * max(m.x, max(m.y, m.z)));
        let c0 = cell_of(lo - g - extent - slack, inv);
        let c1 = cell_of(hi + g + slack, inv);
        // The cells of the range in one loop (z slowest, x fastest: a row is a run of
        // buckets; core::broad::query's order), then the wide boxes' bucket whole. A range
        // of more than TRI_QUERY_CELLS cells: the grid's entries in their order, the wide
        // boxes' last.
        let span = vec3<u32>(c1 - c0) + vec3<u32>(1u);
        let most = TRI_QUERY_CELLS;
        let scan = span.x > most || span.y > most || span.z > most || span.x * span.y > most
            || span.x * span.y * span.z > most;
        var cells = span.x * span.y * span.z;
        var e = 0u;
        var end = 0u;
        var cell = 0u;
        var c = c0;
        var row = 0u;
        var step = vec3<u32>(0u);
        // Whether the walk is in the wide boxes' bucket (or a scan): no entry's cell to test.
        var wide = scan;
        if scan {
            cells = 0u;
            e = bucket_start(grid);
            end = bucket_end(grid + buckets());
        }
        loop {
            if e >= end {
                if cell < cells {
                    // The next cell's bucket (counters: no division a cell).
                    c = c0 + vec3<i32>(step);
                    if step.x == 0u {
                        row = row_start(c.y, c.z);
                    }
                    let k = grid + ((row + bitcast<u32>(c.x)) & (buckets() - 1u));
                    e = bucket_start(k);
                    end = bucket_end(k);
                    cell += 1u;
                    step.x += 1u;
                    if step.x == span.x {
                        step.x = 0u;
                        step.y += 1u;
                        if step.y == span.y {
                            step.y = 0u;
                            step.z += 1u;
                        }
                    }
                    continue;
                }
                if wide {
                    break;
                }
                wide = true;
                e = bucket_start(grid + buckets());
                end = bucket_end(grid + buckets());
                continue;
            }
            let other = load_int(e);
            e += 1u;
            if other < first {
                continue;
            }
            let b = prim_box(offset + other);
            if (!wide && any(cell_of(b.lo, inv) != c)) || any(b.lo - g > hi) || any(lo > b.hi + g) {
                continue;
            }
            var d = 0.0;
            if vertex {
                let t = tri_at(other);
                if t.x == o || t.y == o || t.z == o {
                    continue;
                }
                d = len3(point_triangle(lo, at3(t.x), at3(t.y), at3(t.z)).q - lo);
                if !(d < reach) {
                    continue;
                }
                if !again {
                    lower(o, d);
                    lower(t.x, d);
                    lower(t.y, d);
                    lower(t.z, d);
                }
            } else {
                let f = edge_at(other);
                if f.x == own.x || f.x == own.y || f.y == own.x || f.y == own.y {
                    continue;
                }
                let r = edge_edge(at3(own.x), at3(own.y), at3(f.x), at3(f.y));
                d = len3(r.p - r.q);
                if !(d < reach) {
                    continue;
                }
                if !again {
                    lower(own.x, d);
                    lower(own.y, d);
                    lower(f.x, d);
                    lower(f.y, d);
                }
            }
            if !again {
                if found < TRI_SLOTS {
                    keep(o, found, other, d);
                }
            } else if found >= TRI_SLOTS {
                replace(o, other, d);
            }
            found += 1u;
        }
    }
    return found;
}

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let o = flat_id(id, groups);
    if o >= num_owners() {
        return;
    }
    let found = walk(o, false);
    if found > TRI_SLOTS {
        walk(o, true);
    }
    atomicStore(&tri_ints[ib() + owners_at() + o], found);
    if found > 0u {
        atomicAdd(&tri_ints[ib() + TRI_AT_PAIRS], found);
    }
    if found > TRI_SLOTS {
        atomicAdd(&tri_ints[ib() + TRI_AT_OVERFLOW], found - TRI_SLOTS);
    }
}
