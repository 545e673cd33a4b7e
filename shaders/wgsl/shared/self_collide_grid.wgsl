// The grid's side of the self-collision response (self_collide, self_collide_friction):
// which particles of a grid may push each other.

// core::cpu::self_collide::candidate_coords: outside the springs' 5 x 5 stencil and
// farther apart at rest than twice the thickness.
// (Written without branches here and below: on lavapipe every branch is masks on both
// sides, and an early return is one more.)
fn candidates(a: vec2<i32>, b: vec2<i32>) -> bool {
    let d = a - b;
    let t2 = 2.0 * p.self_thickness;
    return any(abs(d) > vec2<i32>(2)) && f32(d.x * d.x + d.y * d.y) * (p.spacing * p.spacing) > t2 * t2;
}

// The pos.w of the particle whose slot word is w: a grid's is 0 pinned, 1 free (from the
// word alone).
fn other_mobility(w: u32, hit: bool) -> f32 {
    return select(1.0, 0.0, (w & PINNED) != 0u);
}

// A grid's contact: outside the springs' stencil (by the slot word's coordinates) and close.
fn contact(m: Mover, w: u32, close: bool) -> bool {
    let qc = vec2<u32>(w & COORD_MASK, (w >> COORD_BITS) & COORD_MASK);
    return candidates(m.me, vec2<i32>(qc)) && close;
}
