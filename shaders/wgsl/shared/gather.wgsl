// The spring gather (needs state.wgsl and table.wgsl or table_tex.wgsl).

// The interior's shared spring constants (the thesis's constant memory).
@group(0) @binding(16) var<uniform> interior: InteriorSlots;

// core::cpu::springs::gather_at: f plus the springs of particle i, in slot order.
fn springs_at(i: u32, f: vec4<f32>) -> vec4<f32> {
    let inv_dt = 1.0 / p.dt;
    let xa = pos[i].xyz;
    let va = xa - prev[i].xyz;
    var acc = f.xyz;
    if interior.enabled != 0u && is_interior(i, p.n) {
        // Neighbours by offset, constants from the uniform block: no table reads.
        for (var s = 0u; s < SLOTS; s++) {
            let slot = interior.slots[s];
            let b = u32(i32(i) + SLOT_DI[s] + SLOT_DJ[s] * i32(p.n));
            let xb = pos[b].xyz;
            let vb = xb - prev[b].xyz;
            acc += spring_force(xa - xb, va - vb, slot, inv_dt);
        }
        return vec4<f32>(acc, 0.0);
    }
    for (var s = 0u; s < SLOTS; s++) {
        let slot = slot_at(i, s);
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
