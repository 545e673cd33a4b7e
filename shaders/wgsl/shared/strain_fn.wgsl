// The strain limit's arithmetic per spring and per particle (core::cpu::strain_limit),
// shared by its pass (shared/strain_limit_pass.wgsl), its count (strain_count.wgsl) and the
// tiled substep (substep_tile.wgsl), which differ only in where the points come from. The
// includer defines `pin_point(pin)`: a pin's current position, for the tethers.

@group(0) @binding(8) var<storage, read> tethers: array<Tether>;

// 1 where the spring from xi to xb4 (rest length `rest`) is over the limit, else 0
// (core::cpu::strain_limit::count_at): a spring is over the limit exactly when the pass
// finds it so (the same length, the same comparison).
fn over(xi: vec3<f32>, xb4: vec4<f32>, rest: f32) -> f32 {
    let d = xb4.xyz - xi;
    let len = len3(d);
    return select(0.0, 1.0, len > (1.0 + p.strain_limit) * rest);
}

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

// Adds the share of the spring to particle b at xb4 (rest length `rest`) to c when it is
// stretched past the limit, divided by the larger of the two ends' counts ci and cb (the
// same at both ends: the momentum stays); xi and wi are the particle's position and
// mobility.
fn limit_spring(
    c: ptr<function, Correction>,
    b: u32,
    xb4: vec4<f32>,
    rest: f32,
    xi: vec3<f32>,
    wi: f32,
    ci: f32,
    cb: f32
) {
    let stretch = 1.0 + p.strain_limit;
    let aim = 1.0 + STRAIN_AIM * p.strain_limit;
    let d = xb4.xyz - xi;
    let len = len3(d);
    if len > stretch * rest {
        let wb = mobility(b, xb4.w);
        // max(…, 1): ci ≥ 1 when the counts are this pass's; never a division by 0.
        (*c).sum += d * (wi * (len - aim * rest) / ((wi + wb) * len * max(max(ci, cb), 1.0)));
        (*c).count += 1.0;
    }
}

// The corrected position of particle i (at x4, mobility wi) from correction c, pulled back
// by its tethers; x4 itself when it does not move (wi = 0).
fn finish(i: u32, x4: vec4<f32>, wi: f32, c: Correction) -> vec4<f32> {
    var x = x4.xyz;
    if c.count > 0.0 {
        x = x4.xyz + c.sum;
    }
    let stretch = 1.0 + p.strain_limit;
    for (var t = 0u; t < TETHER_SLOTS; t++) {
        let tether = tethers[i * TETHER_SLOTS + t];
        let pin = pin_point(u32(max(tether.pin, 0)));
        let d = x - pin;
        let len = len3(d);
        let max_len = stretch * tether.rest;
        if tether.pin >= 0 && len > max_len {
            x = pin + d * (max_len / len);
        }
    }
    return select(vec4<f32>(x, x4.w), x4, wi == 0.0);
}

