// The contact between triangles' buffers and geometry (core::cpu::tri_contact, whose
// functions are these kernels' twins; core::tri_contact for the closest points). Every
// expression is written as core computes it, products and sums left to right with dot3,
// so that every API computes the twins' bits.
@group(0) @binding(9) var<storage, read> triangles: array<u32>;
// [triangles, edges, buckets, 0], then two vertices an edge.
@group(0) @binding(38) var<storage, read> tri_edges: array<u32>;
// The integers (core::cpu::tri_contact::TriLayout): scalars, the grids, the owners'
// counts, the particles' sums (i32 as u32: a two's complement add is the same add).
@group(0) @binding(40) var<storage, read_write> tri_ints: array<atomic<u32>>;
// TRI_SLOTS pairs an owner.
@group(0) @binding(41) var<storage, read_write> tri_pairs: array<u32>;

fn tris_len() -> u32 {
    return tri_edges[0];
}

fn edges_len() -> u32 {
    return tri_edges[1];
}

fn buckets() -> u32 {
    return tri_edges[2];
}

fn edge_at(e: u32) -> vec2<u32> {
    return vec2<u32>(tri_edges[4u + 2u * e], tri_edges[5u + 2u * e]);
}

fn tri_at(t: u32) -> vec3<u32> {
    return vec3<u32>(triangles[3u * t], triangles[3u * t + 1u], triangles[3u * t + 2u]);
}

// VBD's contact terms, after the scalars: VBD_TERMS words a particle
// (core::cpu::tri_contact::TriLayout::vbd).
fn vbd_terms_at() -> u32 {
    return TRI_AT_WORDS;
}

fn grid_at() -> u32 {
    return TRI_AT_WORDS + VBD_TERMS * num_particles();
}

fn entries_at() -> u32 {
    return grid_at() + 2u * (buckets() + 1u);
}

fn owners_at() -> u32 {
    return entries_at() + tris_len() + edges_len();
}

fn sums_at() -> u32 {
    return owners_at() + num_particles() + edges_len();
}

fn num_owners() -> u32 {
    return num_particles() + edges_len();
}

// A batch of worlds (a kernel's `_w` twin) lays each world's integers and pairs after the
// worlds' before it (core::cpu::tri_contact::TriLayout::words and pair_words a world):
// where the world's start, 0 in a single run. world_begin (the twin calls it after its
// first statement) finds them once. A world's starts and bounds are by particle.
var<private> world_ints: u32;
var<private> world_pairs: u32;

fn world_begin() {
    world_ints = world_index * (sums_at() + 4u * num_particles());
    world_pairs = world_index * (2u * num_owners() * TRI_SLOTS);
}

fn ib() -> u32 {
    return world_ints;
}

fn pb() -> u32 {
    return world_pairs;
}

fn load_int(k: u32) -> u32 {
    return atomicLoad(&tri_ints[ib() + k]);
}

fn load_f(k: u32) -> f32 {
    return bitcast<f32>(atomicLoad(&tri_ints[ib() + k]));
}

fn at3(k: u32) -> vec3<f32> {
    return pos[world_base + k].xyz;
}

// core's Vec3::cross, spelled out (see dot3).
fn cross3(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y);
}

// core's Vec3::normalize: v times one over its length.
fn normalize3(v: vec3<f32>) -> vec3<f32> {
    return v * (1.0 / len3(v));
}

fn finite3(v: vec3<f32>) -> bool {
    let a = abs(v);
    return a.x <= 3.40282347e38 && a.y <= 3.40282347e38 && a.z <= 3.40282347e38;
}

// core::tri_contact::point_triangle: the closest point of triangle (a, b, c) to x, its
// weights on (a, b, c) in the result's first three and the point after.
struct OnTriangle {
    w: vec3<f32>,
    q: vec3<f32>,
}

fn point_triangle(x: vec3<f32>, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> OnTriangle {
    let ab = b - a;
    let ac = c - a;
    let ap = x - a;
    let d1 = dot3(ab, ap);
    let d2 = dot3(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return OnTriangle(vec3<f32>(1.0, 0.0, 0.0), a);
    }
    let bp = x - b;
    let d3 = dot3(ab, bp);
    let d4 = dot3(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return OnTriangle(vec3<f32>(0.0, 1.0, 0.0), b);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 * (1.0 / (d1 - d3));
        return OnTriangle(vec3<f32>(1.0 - v, v, 0.0), a + ab * v);
    }
    let cp = x - c;
    let d5 = dot3(ab, cp);
    let d6 = dot3(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return OnTriangle(vec3<f32>(0.0, 0.0, 1.0), c);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 * (1.0 / (d2 - d6));
        return OnTriangle(vec3<f32>(1.0 - w, 0.0, w), a + ac * w);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let e1 = d4 - d3;
        let e2 = d5 - d6;
        let w = e1 * (1.0 / (e1 + e2));
        return OnTriangle(vec3<f32>(0.0, 1.0 - w, w), b + (c - b) * w);
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    return OnTriangle(vec3<f32>(1.0 - v - w, v, w), a + ab * v + ac * w);
}

// core::tri_contact::edge_edge: the closest points of p0–p1 and q0–q1, their parameters.
struct OnEdges {
    s: f32,
    t: f32,
    p: vec3<f32>,
    q: vec3<f32>,
}

fn edges_at(p0: vec3<f32>, d1: vec3<f32>, q0: vec3<f32>, d2: vec3<f32>, s: f32, t: f32) -> OnEdges {
    return OnEdges(s, t, p0 + d1 * s, q0 + d2 * t);
}

fn edge_edge(p0: vec3<f32>, p1: vec3<f32>, q0: vec3<f32>, q1: vec3<f32>) -> OnEdges {
    let d1 = p1 - p0;
    let d2 = q1 - q0;
    let r = p0 - q0;
    let a = dot3(d1, d1);
    let e = dot3(d2, d2);
    let f = dot3(d2, r);
    if a == 0.0 && e == 0.0 {
        return edges_at(p0, d1, q0, d2, 0.0, 0.0);
    }
    if a == 0.0 {
        return edges_at(p0, d1, q0, d2, 0.0, clamp(f * (1.0 / e), 0.0, 1.0));
    }
    let c = dot3(d1, r);
    if e == 0.0 {
        return edges_at(p0, d1, q0, d2, clamp(-c * (1.0 / a), 0.0, 1.0), 0.0);
    }
    let b = dot3(d1, d2);
    let denom = a * e - b * b;
    if denom <= 1e-6 * a * e {
        let s0 = clamp(dot3(q0 - p0, d1) * (1.0 / a), 0.0, 1.0);
        let s1 = clamp(dot3(q1 - p0, d1) * (1.0 / a), 0.0, 1.0);
        let s = 0.5 * (s0 + s1);
        let t = clamp(dot3(p0 + d1 * s - q0, d2) * (1.0 / e), 0.0, 1.0);
        return edges_at(p0, d1, q0, d2, s, t);
    }
    var s = clamp((b * f - c * e) * (1.0 / denom), 0.0, 1.0);
    var t = (b * s + f) * (1.0 / e);
    if t < 0.0 {
        t = 0.0;
        s = clamp(-c * (1.0 / a), 0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = clamp((b - c) * (1.0 / a), 0.0, 1.0);
    }
    return edges_at(p0, d1, q0, d2, s, t);
}

// A pair's sides (core::cpu::tri_contact's Sides): vertices, weights and closest point
// on each, and the normal for when the points coincide.
struct Sides {
    a: vec3<u32>,
    wa: vec3<f32>,
    p: vec3<f32>,
    b: vec3<u32>,
    wb: vec3<f32>,
    q: vec3<f32>,
    fallback: vec3<f32>,
}

// `w` through a word the compiler cannot know is zero (the edges' header's fourth), so
// that a side's weights (1 − s, s) stay opaque: Mesa's GLSL path otherwise finds a lerp
// in every (1 − s)·a + s·b the response sums (the velocity at a point, Σ w² / m) and
// computes it as s·(b − a) + a fused, a last bit off the twin's.
fn opaque(w: vec3<f32>) -> vec3<f32> {
    return bitcast<vec3<f32>>(bitcast<vec3<u32>>(w) | vec3<u32>(tri_edges[3]));
}

// Owner o's pair with primitive `other`: a vertex and a triangle, or two edges.
fn sides(o: u32, other: u32) -> Sides {
    let np = num_particles();
    if o < np {
        let tri = tri_at(other);
        let x = at3(o);
        let a = at3(tri.x);
        let b = at3(tri.y);
        let c = at3(tri.z);
        let r = point_triangle(x, a, b, c);
        return Sides(vec3<u32>(o), vec3<f32>(1.0, 0.0, 0.0), x, tri, opaque(r.w), r.q, normalize3(cross3(b - a, c - a)));
    }
    let e = edge_at(o - np);
    let g = edge_at(other);
    let a = at3(e.x);
    let b = at3(e.y);
    let c = at3(g.x);
    let d = at3(g.y);
    let r = edge_edge(a, b, c, d);
    let n = normalize3(cross3(b - a, d - c));
    return Sides(vec3<u32>(e.x, e.y, e.y), opaque(vec3<f32>(1.0 - r.s, r.s, 0.0)), r.p, vec3<u32>(g.x, g.y, g.y),
        opaque(vec3<f32>(1.0 - r.t, r.t, 0.0)), r.q, n);
}

fn mass_term(ks: vec3<u32>, ws: vec3<f32>) -> f32 {
    var m = 0.0;
    for (var i = 0u; i < 3u; i++) {
        m = m + pos[world_base + ks[i]].w * ws[i] * ws[i];
    }
    return m;
}

// The velocity of a side's point: Σ w_i v_i in the order of its vertices.
fn speed_of(ks: vec3<u32>, ws: vec3<f32>) -> vec3<f32> {
    var v = vec3<f32>(0.0);
    for (var i = 0u; i < 3u; i++) {
        v = v + vel[world_base + ks[i]].xyz * ws[i];
    }
    return v;
}

// A pair's response (core::cpu::tri_contact::response): `ok` where it has one.
// The distance between a pair's closest points and the unit normal from q to p (the
// fallback where they coincide; NaN for degenerate primitives, which each caller refuses):
// core::tri_contact::Sides::gap, for the response and VBD's terms (tri_vbd.wgsl).
struct Gap {
    d: f32,
    n: vec3<f32>,
}

fn gap(s: Sides) -> Gap {
    let d = len3(s.p - s.q);
    var n = s.fallback;
    if d > 0.0 {
        n = (s.p - s.q) * (1.0 / d);
    }
    return Gap(d, n);
}

struct Response {
    ok: bool,
    s: Sides,
    m: f32,
    change: vec3<f32>,
}

fn response(o: u32, other: u32, velocity: bool) -> Response {
    let s = sides(o, other);
    let t = p.self_thickness;
    if !(t > 0.0) {
        return Response(false, s, 0.0, vec3<f32>(0.0));
    }
    let g = gap(s);
    let d = g.d;
    let n = g.n;
    let m = mass_term(s.a, s.wa) + mass_term(s.b, s.wb);
    if !velocity {
        return Response(m > 0.0 && finite3(n) && d < t, s, m, n * (t - d));
    }
    if m == 0.0 || !finite3(n) {
        return Response(false, s, m, vec3<f32>(0.0));
    }
    let rel = speed_of(s.a, s.wa) - speed_of(s.b, s.wb);
    let vn = dot3(rel, n);
    let want = (t - d) * (1.0 / p.dt);
    if vn >= want {
        return Response(false, s, m, vec3<f32>(0.0));
    }
    let dn = want - vn;
    let slide = rel - n * vn;
    let sl = len3(slide);
    let ms = mu_static();
    let mk = mu_kinetic();
    var stop = vec3<f32>(0.0);
    if sl == 0.0 || (ms == 0.0 && mk == 0.0) {
        stop = vec3<f32>(0.0);
    } else if sl <= ms * dn {
        stop = -slide;
    } else {
        stop = -slide * min(mk * dn * (1.0 / sl), 1.0);
    }
    return Response(true, s, m, n * dn + stop);
}

// The fixed point of a pass's sums (core::cpu::tri_contact::unit).
fn pass_unit(velocity: bool) -> f32 {
    if velocity {
        return p.self_thickness * (1.0 / p.dt) * (1.0 / CONTACT_UNITS);
    }
    return p.self_thickness * (1.0 / CONTACT_UNITS);
}

// Owner o's count of pairs kept.
fn kept(o: u32) -> u32 {
    return min(load_int(owners_at() + o), TRI_SLOTS);
}

// tri_impulse_count and tri_separate_count: one more in the count of each vertex a
// response of owner o moves (word 3 of its sums).
fn count_pass(o: u32, velocity: bool) {
    let sums = sums_at();
    for (var k = 0u; k < kept(o); k++) {
        let r = response(o, tri_pairs[pb() + o * TRI_SLOTS + k], velocity);
        if !r.ok {
            continue;
        }
        for (var i = 0u; i < 3u; i++) {
            if r.s.wa[i] != 0.0 {
                atomicAdd(&tri_ints[ib() + sums + 4u * r.s.a[i] + 3u], 1u);
            }
            if r.s.wb[i] != 0.0 {
                atomicAdd(&tri_ints[ib() + sums + 4u * r.s.b[i] + 3u], 1u);
            }
        }
    }
}

fn add_share(sums: u32, k: u32, d: vec3<f32>) {
    for (var c = 0u; c < 3u; c++) {
        atomicAdd(&tri_ints[ib() + sums + 4u * k + c], bitcast<u32>(i32(d[c])));
    }
}

// tri_impulse_share and tri_separate_share: owner o's responses spread over their
// vertices into the sums; the responses counted.
fn share_pass(o: u32, velocity: bool) {
    let sums = sums_at();
    let u = pass_unit(velocity);
    var responses = 0u;
    for (var k = 0u; k < kept(o); k++) {
        let r = response(o, tri_pairs[pb() + o * TRI_SLOTS + k], velocity);
        if !r.ok {
            continue;
        }
        responses += 1u;
        var most = 1i;
        for (var i = 0u; i < 3u; i++) {
            if r.s.wa[i] != 0.0 {
                most = max(most, bitcast<i32>(load_int(sums + 4u * r.s.a[i] + 3u)));
            }
            if r.s.wb[i] != 0.0 {
                most = max(most, bitcast<i32>(load_int(sums + 4u * r.s.b[i] + 3u)));
            }
        }
        let scale = (1.0 / f32(most)) * (1.0 / r.m) * (1.0 / u);
        for (var i = 0u; i < 3u; i++) {
            if r.s.wa[i] != 0.0 {
                add_share(sums, r.s.a[i], r.change * (1.0 * pos[world_base + r.s.a[i]].w * r.s.wa[i] * scale));
            }
        }
        for (var i = 0u; i < 3u; i++) {
            if r.s.wb[i] != 0.0 {
                add_share(sums, r.s.b[i], r.change * (-1.0 * pos[world_base + r.s.b[i]].w * r.s.wb[i] * scale));
            }
        }
    }
    if responses > 0u {
        atomicAdd(&tri_ints[ib() + select(TRI_AT_PUSHED, TRI_AT_SLOWED, velocity)], responses);
    }
}

// Particle i's sums in the pass's units, the sums cleared (tri_impulse_apply and
// tri_separate_apply add them).
fn take_sums(i: u32, velocity: bool) -> vec3<f32> {
    let sums = sums_at() + 4u * i;
    let u = pass_unit(velocity);
    let d = vec3<f32>(
        f32(bitcast<i32>(atomicLoad(&tri_ints[ib() + sums]))) * u,
        f32(bitcast<i32>(atomicLoad(&tri_ints[ib() + sums + 1u]))) * u,
        f32(bitcast<i32>(atomicLoad(&tri_ints[ib() + sums + 2u]))) * u,
    );
    for (var c = 0u; c < 4u; c++) {
        atomicStore(&tri_ints[ib() + sums + c], 0u);
    }
    return d;
}

// A box corner's cell (core::broad::cell_of).
fn cell_of(x: vec3<f32>, inv_cell: f32) -> vec3<i32> {
    return vec3<i32>(clamp(floor(x * inv_cell), vec3<f32>(-1e6), vec3<f32>(1e6)));
}

// Whether a box is wider than BIG_CELLS cells on some axis (core::broad::is_big): listed
// in the bucket after its grid's, which every query reads whole.
fn is_big(b: Box, cell: f32) -> bool {
    let e = b.hi - b.lo;
    return max(e.x, max(e.y, e.z)) > BIG_CELLS * cell;
}

// Primitive o's box (triangles first, then edges): lowest and highest corner.
struct Box {
    lo: vec3<f32>,
    hi: vec3<f32>,
}

fn prim_box(o: u32) -> Box {
    if o < tris_len() {
        let t = tri_at(o);
        let a = at3(t.x);
        let b = at3(t.y);
        let c = at3(t.z);
        return Box(min(min(a, b), c), max(max(a, b), c));
    }
    let e = edge_at(o - tris_len());
    let a = at3(e.x);
    let b = at3(e.y);
    return Box(min(a, b), max(a, b));
}

// Primitive o's bucket among both grids' (each buckets() and one for its wide boxes;
// its grid's first bucket added: core::broad::slot_of).
fn bucket_of(b: Box, o: u32, cell: f32) -> u32 {
    let slot = select(bucket(cell_of(b.lo, 1.0 / cell), buckets()), buckets(), is_big(b, cell));
    return select(buckets() + 1u, 0u, o < tris_len()) + slot;
}

// Bucket k's entries, after the scatter: [start, end).
fn bucket_start(k: u32) -> u32 {
    if k == 0u {
        return entries_at();
    }
    return entries_at() + load_int(grid_at() + k - 1u);
}

fn bucket_end(k: u32) -> u32 {
    return entries_at() + load_int(grid_at() + k);
}
