// The spring gather (needs state.wgsl and table.wgsl or table_tex.wgsl).

// The interior's shared spring constants (the thesis's constant memory).
@group(0) @binding(16) var<uniform> interior_slots: InteriorSlots;
// Copied at the top of the kernel like `p`.
var<private> interior: InteriorSlots;

// The force of interior slot s on a particle at xa with velocity·dt va: the neighbour at
// offset (di, dj) in the grid, the constants from the uniform block.
fn interior_spring(i: u32, di: i32, dj: i32, s: u32, xa: vec3<f32>, va: vec3<f32>, inv_dt: f32) -> vec3<f32> {
    let b = u32(i32(i) + di + dj * i32(p.n));
    let xb = pos[b].xyz;
    let vb = xb - prev[b].xyz;
    return spring_force(xa - xb, va - vb, interior.slots[s], inv_dt);
}

// core::cpu::springs::gather_at: f plus the springs of particle i (at xa, with velocity·dt
// va), in slot order.
//
// Interior particles take their neighbours by offset and the constants from the uniform
// block, written out slot by slot (core::grid::SLOT_OFFSETS) so that every offset and
// uniform address is a compile-time constant. Border particles walk their table in a loop
// that has no iteration for interior ones: drivers that run a SIMD group through both
// sides of a branch (llvmpipe) skip a loop that no lane enters, but not an `if`.
fn springs_at(i: u32, xa: vec3<f32>, va: vec3<f32>, f: vec4<f32>) -> vec4<f32> {
    let inv_dt = 1.0 / p.dt;
    var acc = f.xyz;
    let inner = interior.enabled != 0u && is_interior(i, p.n);
    if inner {
        acc += interior_spring(i, -1, 0, 0u, xa, va, inv_dt);
        acc += interior_spring(i, 1, 0, 1u, xa, va, inv_dt);
        acc += interior_spring(i, 0, -1, 2u, xa, va, inv_dt);
        acc += interior_spring(i, 0, 1, 3u, xa, va, inv_dt);
        acc += interior_spring(i, -1, -1, 4u, xa, va, inv_dt);
        acc += interior_spring(i, 1, -1, 5u, xa, va, inv_dt);
        acc += interior_spring(i, -1, 1, 6u, xa, va, inv_dt);
        acc += interior_spring(i, 1, 1, 7u, xa, va, inv_dt);
        acc += interior_spring(i, -2, 0, 8u, xa, va, inv_dt);
        acc += interior_spring(i, 2, 0, 9u, xa, va, inv_dt);
        acc += interior_spring(i, 0, -2, 10u, xa, va, inv_dt);
        acc += interior_spring(i, 0, 2, 11u, xa, va, inv_dt);
    }
    let table_slots = select(SLOTS, 0u, inner);
    for (var s = 0u; s < table_slots; s++) {
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
