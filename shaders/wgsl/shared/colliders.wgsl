// The colliders' contact geometry, one function per shape (core::contact: sphere_contact,
// box_contact, rod_contact for capsules and cylinders, body_contact; needs state.wgsl),
// and collide's walk over them. The build also emits every kernel
// that includes this file as `<kernel>_cu`, with the first two declarations swapped for
// uniform blocks of MAX_COLLIDERS entries (the thesis's constant memory:
// `colliders=uniform`). The capsules and the bodies' fields stay in storage.

@group(0) @binding(12) var<storage, read> spheres: array<Sphere>;
@group(0) @binding(13) var<storage, read> boxes: array<Aabb>;
// The rods and bodies (core::sdf, layout::Buf::Shapes): MAX_BODIES heads of
// SDF_HEAD_FLOATS floats (R's columns, translation, velocity, spin, the grid's first point
// and spacing, its points per axis and first value), the rods from SHAPES_RODS_AT (16
// floats each: capsules, then cylinders), the bodies' values from SHAPES_VALUES_AT.
@group(0) @binding(34) var<storage, read> shapes: array<f32>;

fn shapes_vec4(i: u32) -> vec4<f32> {
    return vec4<f32>(shapes[i], shapes[i + 1u], shapes[i + 2u], shapes[i + 3u]);
}

// Rod k.
fn rod_at(k: u32) -> Rod {
    let b = SHAPES_RODS_AT + 16u * k;
    return Rod(shapes_vec4(b), shapes_vec4(b + 4u), shapes_vec4(b + 8u), shapes_vec4(b + 12u));
}

// The surface's velocity at `arm` from the centre of a shape moving at v and spinning at
// spin (surface_vel); zero where nothing in the scene moves (USES_MOTION false: every
// velocity and spin is zero, and so, to the bit, is surface_vel's sum).
fn moving_vel(v: vec3<f32>, spin: vec3<f32>, arm: vec3<f32>) -> vec3<f32> {
    if USES_MOTION {
        return surface_vel(v, spin, arm);
    }
    return vec3<f32>(0.0);
}

// A point's contact with a shape grown by a reach (core::contact::Contact): `hit` false
// where there is none.
struct Contact {
    hit: bool,
    depth: f32,
    n: vec3<f32>,
    at: vec3<f32>,
    vs: vec3<f32>,
}

const NO_CONTACT = Contact(false, 0.0, vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(0.0), vec3<f32>(0.0));

// A direction away from a centre d long dist, or up at the centre (core::contact::away).
fn away(d: vec3<f32>, dist: f32) -> vec3<f32> {
    if dist > 1e-12 {
        return d / dist;
    }
    return vec3<f32>(0.0, 1.0, 0.0);
}

// The floor at height y (core::contact::floor_contact).
fn floor_contact(y: f32, x: vec3<f32>, reach: f32) -> Contact {
    let top = y + reach;
    if x.y >= top {
        return NO_CONTACT;
    }
    return Contact(true, top - x.y, vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(x.x, top, x.z), vec3<f32>(0.0));
}

// core::contact's `impl Shape for Sphere`.
fn sphere_contact(s: Sphere, x: vec3<f32>, reach: f32) -> Contact {
    let r = s.radius + reach;
    let d = x - s.center;
    let dist2 = dot3(d, d);
    if dist2 >= r * r {
        return NO_CONTACT;
    }
    let dist = sqrt(dist2);
    let n = away(d, dist);
    let arm = n * r;
    return Contact(true, r - dist, n, s.center + arm, moving_vel(s.velocity.xyz, s.spin.xyz, arm));
}

// core::contact's `impl Shape for Aabb`: out through the nearest face.
fn box_contact(b: Aabb, x: vec3<f32>, reach: f32) -> Contact {
    let lo = b.min.xyz - vec3<f32>(reach);
    let hi = b.max.xyz + vec3<f32>(reach);
    if !(all(x > lo) && all(x < hi)) {
        return NO_CONTACT;
    }
    let below = x - lo;
    let above = hi - x;
    var best = below.x;
    var n = vec3<f32>(-1.0, 0.0, 0.0);
    var face = lo.x;
    if above.x < best { best = above.x; n = vec3<f32>(1.0, 0.0, 0.0); face = hi.x; }
    if below.y < best { best = below.y; n = vec3<f32>(0.0, -1.0, 0.0); face = lo.y; }
    if above.y < best { best = above.y; n = vec3<f32>(0.0, 1.0, 0.0); face = hi.y; }
    if below.z < best { best = below.z; n = vec3<f32>(0.0, 0.0, -1.0); face = lo.z; }
    if above.z < best { best = above.z; n = vec3<f32>(0.0, 0.0, 1.0); face = hi.z; }
    let axis = abs(n);
    return Contact(true, best, n, x * (vec3<f32>(1.0) - axis) + axis * face, select(vec3<f32>(0.0), b.velocity.xyz, USES_MOTION));
}

// The midpoint of a rod's axis, (a + b)·½ (core::contact::mid).
fn rod_center(c: Rod) -> vec3<f32> {
    return (c.a.xyz + c.b.xyz) * 0.5;
}

// core::contact::capsule_contact.
fn capsule_contact(c: Rod, x: vec3<f32>, reach: f32) -> Contact {
    let r = c.a.w + reach;
    let a = c.a.xyz;
    let ab = c.b.xyz - a;
    let len2 = dot3(ab, ab);
    var s = 0.0;
    if len2 > 1e-24 {
        s = clamp(dot3(x - a, ab) / len2, 0.0, 1.0);
    }
    let q = a + ab * s;
    let d = x - q;
    let dist2 = dot3(d, d);
    if dist2 >= r * r {
        return NO_CONTACT;
    }
    let dist = sqrt(dist2);
    let n = away(d, dist);
    let at = q + n * r;
    return Contact(true, r - dist, n, at, moving_vel(c.velocity.xyz, c.spin.xyz, at - rod_center(c)));
}

// A unit direction across the unit axis u (core::contact::across).
fn across(u: vec3<f32>) -> vec3<f32> {
    var w = vec3<f32>(0.0, 1.0, 0.0);
    if abs(u.x) < 0.9 {
        w = vec3<f32>(1.0, 0.0, 0.0);
    }
    let p = w - u * dot3(w, u);
    return p / sqrt(dot3(p, p));
}

// core::contact::cylinder_contact: out through the side or the nearer cap.
fn cylinder_contact(c: Rod, x: vec3<f32>, reach: f32) -> Contact {
    let m = rod_center(c);
    let ab = c.b.xyz - c.a.xyz;
    let len = sqrt(dot3(ab, ab));
    let u = ab / len;
    let d = x - m;
    let t = dot3(d, u);
    let radial = d - u * t;
    let rho2 = dot3(radial, radial);
    let r = c.a.w + reach;
    let h = len * 0.5 + reach;
    if rho2 >= r * r || abs(t) >= h {
        return NO_CONTACT;
    }
    let rho = sqrt(rho2);
    let side = r - rho;
    let cap = h - abs(t);
    var depth = cap;
    var n = u;
    if t < 0.0 {
        n = -u;
    }
    var at = x + n * cap;
    if side < cap {
        depth = side;
        n = across(u);
        if rho > 1e-12 {
            n = radial / rho;
        }
        at = m + u * t + n * r;
    }
    return Contact(true, depth, n, at, moving_vel(c.velocity.xyz, c.spin.xyz, at - m));
}

// core::contact::cone_contact: the base a disc about a, the apex at b; out through the
// side or the base.
fn cone_contact(c: Rod, x: vec3<f32>, reach: f32) -> Contact {
    let a = c.a.xyz;
    let ab = c.b.xyz - a;
    let len = sqrt(dot3(ab, ab));
    let u = ab / len;
    let d = x - a;
    let t = dot3(d, u);
    let radial = d - u * t;
    let rho = sqrt(dot3(radial, radial));
    let r = c.a.w;
    let slant = sqrt(r * r + len * len);
    let side = reach - (t * r + (rho - r) * len) / slant;
    let base = reach + t;
    if !(side > 0.0 && base > 0.0) {
        return NO_CONTACT;
    }
    var depth = base;
    var n = -u;
    if side < base {
        var out = across(u);
        if rho > 1e-12 {
            out = radial / rho;
        }
        depth = side;
        n = u * (r / slant) + out * (len / slant);
    }
    let at = x + n * depth;
    return Contact(true, depth, n, at, moving_vel(c.velocity.xyz, c.spin.xyz, at - rod_center(c)));
}

// Rod k's contact, by its kind (core::contact's `impl Shape for Rod`).
fn rod_contact(k: u32, x: vec3<f32>, reach: f32) -> Contact {
    let c = rod_at(k);
    if c.b.w == ROD_CYLINDER {
        return cylinder_contact(c, x, reach);
    }
    if c.b.w == ROD_CONE {
        return cone_contact(c, x, reach);
    }
    return capsule_contact(c, x, reach);
}

// Floats j .. j+2 of body k's head.
fn body_vec(k: u32, j: u32) -> vec3<f32> {
    let b = k * SDF_HEAD_FLOATS + j;
    return vec3<f32>(shapes[b], shapes[b + 1u], shapes[b + 2u]);
}

fn lerp1(a: f32, b: f32, t: f32) -> f32 {
    return a + (b - a) * t;
}

// Body k's field at x (core::cpu::collide::body_sample): φ and the world direction of
// its gradient; `valid` false outside its grid or where the cell's first value shows φ is
// at least `reach` all over the cell (core::sdf::BAND_CELLS: one load, not eight).
struct BodySample {
    phi: f32,
    n: vec3<f32>,
    valid: bool,
}

// Where x lies in body k's grid: g, in cells from its first point (the frame of R's
// columns about its translation), the last point's g (`top`), the cell h, the points per
// axis; `inside` false outside the grid (both homes of the field: body_sample and
// shared/sdf_image.wgsl's).
struct BodyAt {
    g: vec3<f32>,
    top: vec3<f32>,
    h: f32,
    dims: vec3<u32>,
    inside: bool,
}

fn body_at(k: u32, x: vec3<f32>) -> BodyAt {
    let hb = k * SDF_HEAD_FLOATS;
    let c0 = body_vec(k, 0u);
    let c1 = body_vec(k, 4u);
    let c2 = body_vec(k, 8u);
    let d = x - body_vec(k, 12u);
    let q = vec3<f32>(dot3(c0, d), dot3(c1, d), dot3(c2, d));
    let lo = body_vec(k, 24u);
    let h = shapes[hb + 27u];
    let dims = vec3<u32>(bitcast<u32>(shapes[hb + 28u]), bitcast<u32>(shapes[hb + 29u]), bitcast<u32>(shapes[hb + 30u]));
    let g = vec3<f32>((q.x - lo.x) / h, (q.y - lo.y) / h, (q.z - lo.z) / h);
    let top = vec3<f32>(f32(dims.x - 1u), f32(dims.y - 1u), f32(dims.z - 1u));
    let inside = g.x >= 0.0 && g.y >= 0.0 && g.z >= 0.0 && g.x <= top.x && g.y <= top.y && g.z <= top.z;
    return BodyAt(g, top, h, dims, inside);
}

// The world direction of a gradient gr in body k's grid: normalised (up where it
// vanishes), turned by R's columns.
fn body_normal(k: u32, gr: vec3<f32>) -> vec3<f32> {
    let glen = sqrt(dot3(gr, gr));
    var nl = vec3<f32>(0.0, 1.0, 0.0);
    if glen > 1e-12 {
        nl = vec3<f32>(gr.x / glen, gr.y / glen, gr.z / glen);
    }
    return body_vec(k, 0u) * nl.x + body_vec(k, 4u) * nl.y + body_vec(k, 8u) * nl.z;
}

// The gradient (per cell) of the trilinear interpolant of a cell's corner values cijk
// (at x = i, y = j, z = k) at f within the cell (core::sdf::sample_grid's): both homes of
// the field push along it.
fn cell_gradient(
    c000: f32,
    c100: f32,
    c010: f32,
    c110: f32,
    c001: f32,
    c101: f32,
    c011: f32,
    c111: f32,
    f: vec3<f32>,
) -> vec3<f32> {
    return vec3<f32>(
        lerp1(lerp1(c100 - c000, c110 - c010, f.y), lerp1(c101 - c001, c111 - c011, f.y), f.z),
        lerp1(lerp1(c010 - c000, c110 - c100, f.x), lerp1(c011 - c001, c111 - c101, f.x), f.z),
        lerp1(lerp1(c001 - c000, c101 - c100, f.x), lerp1(c011 - c010, c111 - c110, f.x), f.y),
    );
}

fn body_sample(k: u32, x: vec3<f32>, reach: f32) -> BodySample {
    var out = BodySample(0.0, vec3<f32>(0.0, 1.0, 0.0), false);
    let at = body_at(k, x);
    if !at.inside {
        return out;
    }
    let g = at.g;
    let top = at.top;
    let h = at.h;
    let dims = at.dims;
    let first = bitcast<u32>(shapes[k * SDF_HEAD_FLOATS + 31u]);
    let c = min(floor(g), top - vec3<f32>(1.0));
    let f = g - c;
    let sy = dims.x;
    let sz = sy * dims.y;
    let base = SHAPES_VALUES_AT + first + u32(c.x) + sy * u32(c.y) + sz * u32(c.z);
    let c000 = shapes[base];
    if c000 - 1.75 * h >= reach {
        return out;
    }
    let c100 = shapes[base + 1u];
    let c010 = shapes[base + sy];
    let c110 = shapes[base + 1u + sy];
    let c001 = shapes[base + sz];
    let c101 = shapes[base + 1u + sz];
    let c011 = shapes[base + sy + sz];
    let c111 = shapes[base + 1u + sy + sz];
    out.phi = lerp1(
        lerp1(lerp1(c000, c100, f.x), lerp1(c010, c110, f.x), f.y),
        lerp1(lerp1(c001, c101, f.x), lerp1(c011, c111, f.x), f.y),
        f.z,
    );
    out.n = body_normal(k, cell_gradient(c000, c100, c010, c110, c001, c101, c011, c111, f));
    out.valid = true;
    return out;
}

// core::contact's `impl Shape for Body`: pushed along the field's gradient to φ = reach.
fn body_contact(k: u32, x: vec3<f32>, reach: f32) -> Contact {
    let s = body_sample(k, x, reach);
    if !(s.valid && s.phi < reach) {
        return NO_CONTACT;
    }
    let at = x + s.n * (reach - s.phi);
    return Contact(true, reach - s.phi, s.n, at, moving_vel(body_vec(k, 16u), body_vec(k, 20u), at - body_vec(k, 12u)));
}

// core::cpu::collide::collide_at for a free particle (is_free): m pushed out of every
// collider in scene order (core::cpu::Colliders::walk), its velocity relative to their
// surfaces where they move.
fn collided(m: Moved) -> Moved {
    var o = m;
    for (var k = 0u; k < p.num_spheres; k++) {
        o = touched(o, sphere_contact(spheres[k], o.x, p.margin));
    }
    for (var k = 0u; k < p.num_boxes; k++) {
        o = touched(o, box_contact(boxes[k], o.x, p.margin));
    }
    if USES_RODS {
        for (var k = 0u; k < p.num_rods; k++) {
            o = touched(o, rod_contact(k, o.x, p.margin));
        }
    }
    if USES_BODIES {
        for (var k = 0u; k < p.num_bodies; k++) {
            o = touched(o, body_contact(k, o.x, p.margin));
        }
    }
    return o;
}

// m moved to contact c's point, its velocity relative to the surface there (the Rust
// walk's `touch`); m itself where c is no contact.
fn touched(m: Moved, c: Contact) -> Moved {
    if !c.hit {
        return m;
    }
    let hit = surface_contact(c.at, m.v, c.vs, c.n);
    return Moved(hit.x, hit.v);
}
