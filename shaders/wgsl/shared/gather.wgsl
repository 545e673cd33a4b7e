// The per-particle spring table (needs state.wgsl).

@group(0) @binding(6) var<storage, read> slots: array<SpringSlot>;

// core::cpu::springs::gather_at: f plus the springs of particle i, in slot order.
fn springs_at(i: u32, f: vec4<f32>) -> vec4<f32> {
    let inv_dt = 1.0 / p.dt;
    let xa = pos[i].xyz;
    let va = xa - prev[i].xyz;
    var acc = f.xyz;
    for (var s = 0u; s < SLOTS; s++) {
        let slot = slots[i * SLOTS + s];
        if slot.neighbor < 0 {
            continue;
        }
        let b = u32(slot.neighbor);
        let xb = pos[b].xyz;
        let vb = xb - prev[b].xyz;
        acc += spring_force(xa - xb, va - vb, slot, inv_dt);
    }
    return vec4<f32>(acc, 0.0);
}
