// Coulomb friction between particles in contact, for the self-collision response's
// _friction kernels (self_collide_friction, self_collide_mesh_friction: the recipe picks
// them when the parameters have Coulomb's coefficients): each contact's part, summed in
// fixed point beside its push (core::cpu::self_collide::pair_friction).
const FRICTION: bool = true;

// core::cpu::self_collide::STICK: the part of its slip one sticking contact removes.
const STICK: f32 = 0.25;

// core::cpu::self_collide::pair_friction: the relative tangential velocity a contact
// removes (e = xi - xj, d2 = |e|², sep = t - d, w = vi - vj); odd in (e, w) bit for bit.
fn pair_friction(e: vec3<f32>, d2: f32, sep: f32, w: vec3<f32>) -> vec3<f32> {
    let k = dot3(w, e) / d2;
    let vt = w - k * e;
    let vtl = sqrt(dot3(vt, vt));
    let dvn = sep * (1.0 / p.dt);
    let keep = select(STICK, min(STICK, mu_kinetic() * dvn / vtl), vtl > mu_static() * dvn);
    return vt * keep;
}

// core::cpu::self_collide::friction_scale: fixed-point units per μs t / dt.
fn friction_scale() -> f32 {
    return UNITS * p.inv_cell * p.dt / mu_static();
}

// The contact's friction into m's sum (a uniform branch: the same for every invocation):
// against the contact's velocity before the response, from the copy.
fn rub(m: ptr<function, Mover>, e: vec3<f32>, d2: f32, sep: f32, share: f32, w: u32, hit: bool) {
    if coulomb() {
        let vj = vel_copy[world_base + min(slot_particle(w), num_particles() - 1u)].xyz;
        let r = pair_friction(e, d2, sep, (*m).v - vj);
        (*m).rub += select(vec3<i32>(0), vec3<i32>(r * (share * friction_scale())), hit);
    }
}
