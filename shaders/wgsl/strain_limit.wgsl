//! include: table
// strain_limit — per particle, one Jacobi pass of Provot's strain limit plus the tethers
// (core::cpu::strain_limit::limit_at). Reads pos, writes pos_out.
@group(0) @binding(0) var<uniform> p: StepParams;
@group(0) @binding(1) var<storage, read_write> pos: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> pos_out: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read> tethers: array<Tether>;
@group(0) @binding(16) var<uniform> interior: InteriorSlots;

fn mobility(k: u32) -> f32 {
    if i32(k) == p.grab_index {
        return 0.0;
    }
    return pos[k].w;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = flat_id(id, groups);
    if i >= p.n * p.n {
        return;
    }
    let stretch = 1.0 + p.strain_limit;
    let aim = 1.0 + STRAIN_AIM * p.strain_limit;
    let xi = pos[i].xyz;
    let wi = mobility(i);
    if wi == 0.0 {
        pos_out[i] = pos[i];
        return;
    }
    var corr = vec3<f32>(0.0);
    var count = 0.0;
    let inner = interior.enabled != 0u && is_interior(i, p.n);
    for (var s = 0u; s < STRAIN_SLOTS; s++) {
        // Interior: neighbour by offset and rest length from the uniform block.
        var slot: SpringSlot;
        if inner {
            slot = interior.slots[s];
            slot.neighbor = i32(i) + SLOT_DI[s] + SLOT_DJ[s] * i32(p.n);
        } else {
            slot = slot_at(i, s);
        }
        if slot.neighbor < 0 {
            continue;
        }
        let b = u32(slot.neighbor);
        let d = pos[b].xyz - xi;
        let len = length(d);
        if len > stretch * slot.rest {
            let wb = mobility(b);
            corr += d * (wi * (len - aim * slot.rest) / ((wi + wb) * len));
            count += 1.0;
        }
    }
    var x = xi;
    if count > 0.0 {
        x = xi + corr / count;
    }
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
    pos_out[i] = vec4<f32>(x, pos[i].w);
}
