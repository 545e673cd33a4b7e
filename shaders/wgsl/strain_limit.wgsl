//! include: table
// strain_limit — per particle, one Jacobi pass of Provot's strain limit plus the tethers
// (core::cpu::strain_limit::limit_at). Reads pos, writes pos_out.
@group(0) @binding(0) var<uniform> step_params: StepParams;
// Copied from step_params by the kernel's first statement (see shared/state.wgsl).
var<private> p: StepParams;
@group(0) @binding(1) var<storage, read_write> pos: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> pos_out: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read> tethers: array<Tether>;
@group(0) @binding(16) var<uniform> interior_slots: InteriorSlots;
// Copied at the top of the kernel like `p`.
var<private> interior: InteriorSlots;

// Mobility of particle k with pos[k].w = w: 0 when pinned or grabbed.
fn mobility(k: u32, w: f32) -> f32 {
    if i32(k) == p.grab_index {
        return 0.0;
    }
    return w;
}

// The correction sum and count of the springs over their limit.
struct Correction {
    sum: vec3<f32>,
    count: f32,
}

// Adds the share of the spring to neighbour b (rest length `rest`) to c when it is
// stretched past the limit; xi and wi are the particle's position and mobility.
fn limit_spring(c: ptr<function, Correction>, b: u32, rest: f32, xi: vec3<f32>, wi: f32) {
    let stretch = 1.0 + p.strain_limit;
    let aim = 1.0 + STRAIN_AIM * p.strain_limit;
    let xb4 = pos[b];
    let d = xb4.xyz - xi;
    let len = length(d);
    if len > stretch * rest {
        let wb = mobility(b, xb4.w);
        (*c).sum += d * (wi * (len - aim * rest) / ((wi + wb) * len));
        (*c).count += 1.0;
    }
}

// Interior slot s (structural or shear) at grid offset (di, dj).
fn limit_interior(c: ptr<function, Correction>, i: u32, di: i32, dj: i32, s: u32, xi: vec3<f32>, wi: f32) {
    limit_spring(c, u32(i32(i) + di + dj * i32(p.n)), interior.slots[s].rest, xi, wi);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    interior = interior_slots;
    let i = flat_id(id, groups);
    if i >= p.n * p.n {
        return;
    }
    let x4 = pos[i];
    let xi = x4.xyz;
    let wi = mobility(i, x4.w);
    if wi == 0.0 {
        pos_out[i] = x4;
        return;
    }
    var c = Correction(vec3<f32>(0.0), 0.0);
    // Interior: neighbours by offset, rest lengths from the uniform block, slot by slot
    // (core::grid::SLOT_OFFSETS); the border walks its table in a loop that interior
    // particles do not enter (see springs_at in shared/gather.wgsl).
    let inner = interior.enabled != 0u && is_interior(i, p.n);
    if inner {
        limit_interior(&c, i, -1, 0, 0u, xi, wi);
        limit_interior(&c, i, 1, 0, 1u, xi, wi);
        limit_interior(&c, i, 0, -1, 2u, xi, wi);
        limit_interior(&c, i, 0, 1, 3u, xi, wi);
        limit_interior(&c, i, -1, -1, 4u, xi, wi);
        limit_interior(&c, i, 1, -1, 5u, xi, wi);
        limit_interior(&c, i, -1, 1, 6u, xi, wi);
        limit_interior(&c, i, 1, 1, 7u, xi, wi);
    }
    let table_slots = select(STRAIN_SLOTS, 0u, inner);
    for (var s = 0u; s < table_slots; s++) {
        let slot = slot_at(i, s);
        if slot.neighbor >= 0 {
            limit_spring(&c, u32(slot.neighbor), slot.rest, xi, wi);
        }
    }
    var x = xi;
    if c.count > 0.0 {
        x = xi + c.sum / c.count;
    }
    let stretch = 1.0 + p.strain_limit;
    for (var t = 0u; t < TETHER_SLOTS; t++) {
        let tether = tethers[i * TETHER_SLOTS + t];
        if tether.pin < 0 {
            continue;
        }
        let pin = pos[u32(tether.pin)].xyz;
        let d = x - pin;
        let len = length(d);
        let max_len = stretch * tether.rest;
        if len > max_len {
            x = pin + d * (max_len / len);
        }
    }
    pos_out[i] = vec4<f32>(x, x4.w);
}
