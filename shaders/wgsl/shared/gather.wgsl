// The spring gather (needs state.wgsl and table.wgsl or table_tex.wgsl).

@group(0) @binding(16) var<uniform> interior_slots: GridSpringConstants;
// The grid's spring constants (the thesis's constant memory), copied at the top of the
// kernel like `p`; `enabled` when the table is the regular grid's (core's grid_slots).
var<private> interior: GridSpringConstants;

// A particle's position and velocity.
struct Pt {
    x: vec3<f32>,
    v: vec3<f32>,
}

fn point(k: u32) -> Pt {
    return Pt(pos[world_base + k].xyz, vel[world_base + k].xyz);
}

// Grid point (c, r), which may lie outside the grid: its particle's point (particle 0's
// when outside, so that every lane loads something) and whether it is inside.
struct Nb {
    pt: Pt,
    inside: bool,
}

// Whether grid point (c, r) lies on the grid.
fn on_grid(c: i32, r: i32) -> bool {
    let n = i32(p.n);
    return c >= 0 && c < n && r >= 0 && r < n;
}

fn grid_point(c: i32, r: i32) -> Nb {
    let n = i32(p.n);
    let inside = on_grid(c, r);
    return Nb(point(u32(select(0, r * n + c, inside))), inside);
}

// acc plus the force of slot s's spring between a and b, if b exists (acc unchanged
// otherwise, as core's gather skips an empty slot).
fn grid_spring(acc: vec3<f32>, a: Pt, b: Nb, s: u32) -> vec3<f32> {
    let f = spring_force(a.x - b.pt.x, a.v - b.pt.v, interior.slots[s]);
    return select(acc, acc + f, b.inside);
}

// core::cpu::springs::gather_at on a regular grid: f plus the springs of particle a, its
// neighbours s0 … s11 in slot order (core::grid::SLOT_OFFSETS), the constants from the
// uniform block. No table reads and no branches: on drivers that run every branch of a
// SIMD group and emulate storage loads lane by lane (llvmpipe), every load in the code
// costs, taken or not.
fn grid_springs(
    f: vec3<f32>, a: Pt, s0: Nb, s1: Nb, s2: Nb, s3: Nb, s4: Nb, s5: Nb, s6: Nb, s7: Nb, s8: Nb,
    s9: Nb, s10: Nb, s11: Nb,
) -> vec3<f32> {
    var acc = f;
    acc = grid_spring(acc, a, s0, 0u);
    acc = grid_spring(acc, a, s1, 1u);
    acc = grid_spring(acc, a, s2, 2u);
    acc = grid_spring(acc, a, s3, 3u);
    acc = grid_spring(acc, a, s4, 4u);
    acc = grid_spring(acc, a, s5, 5u);
    acc = grid_spring(acc, a, s6, 6u);
    acc = grid_spring(acc, a, s7, 7u);
    acc = grid_spring(acc, a, s8, 8u);
    acc = grid_spring(acc, a, s9, 9u);
    acc = grid_spring(acc, a, s10, 10u);
    acc = grid_spring(acc, a, s11, 11u);
    return acc;
}

// core::cpu::springs::gather_at from the table: f plus the springs of particle i (a = its
// point), in slot order.
fn table_springs(i: u32, a: Pt, f: vec3<f32>) -> vec3<f32> {
    var acc = f;
    let r = slot_row(i);
    for (var s = 0u; s < r.count; s++) {
        let slot = row_slot(i, r, s);
        let other = slot_other(slot);
        if other < 0 {
            continue;
        }
        let b = point(u32(other));
        acc += spring_force(a.x - b.x, a.v - b.v, slot);
    }
    return acc;
}
