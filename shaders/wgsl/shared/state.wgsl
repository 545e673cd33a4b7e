// The particle state and the per-particle kernels that touch only their own particle.

@group(0) @binding(0) var<uniform> step_params: StepParams;
// The step constants, copied from the uniform block (immediates in the `_imm` twins) by
// the first statement of every kernel, outside all control flow: llvmpipe reads uniforms
// as scalars only where every invocation is known to be active, and gathers them lane by
// lane inside any branch (including the one an early `return` opens).
var<private> p: StepParams;
@group(0) @binding(1) var<storage, read_write> pos: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> vel: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> force: array<vec4<f32>>;

fn num_particles() -> u32 {
    return p.num_particles;
}

// core::cpu::mass: the mass of a particle whose pos.w is w (its relative inverse mass):
// the reference mass over w, the reference for a held particle (w = 0). On a grid w is 1
// or 0, so this is exactly p.particle_mass.
fn mass_of(w: f32) -> f32 {
    return mass_with(p.particle_mass, w);
}

// core::cpu::dt_over_mass: dt/m of a particle whose pos.w is w, (dt/m̄)·w (×1 on a grid).
fn dt_over_mass(w: f32) -> f32 {
    let k = p.dt / p.particle_mass;
    return select(k, k * w, w > 0.0);
}

// core::cpu::forces::forces_at with forces_consts_w: f + m g - drag m v for a particle of
// pos.w = w, with v its velocity (passed in, so that a kernel that needs it again loads it
// once).
fn forces_at(f: vec4<f32>, v: vec3<f32>, w: f32) -> vec4<f32> {
    let m = mass_of(w);
    let g = p.gravity.xyz * m;
    let drag = p.air_drag * m;
    return vec4<f32>(f.xyz + g - v * drag, 0.0);
}

// forces_at for a particle of the reference mass (forces_consts): the grid's blocked
// gathers, whose every particle has w = 1 or 0 (held: the reference too).
fn forces_at_mean(f: vec4<f32>, v: vec3<f32>) -> vec4<f32> {
    let g = p.gravity.xyz * p.particle_mass;
    let drag = p.air_drag * p.particle_mass;
    return vec4<f32>(f.xyz + g - v * drag, 0.0);
}

// A particle's position and velocity. The per-particle kernels load each once and store
// each once: on drivers that emulate storage-buffer access lane by lane (llvmpipe) every
// access counts.
struct Moved {
    x: vec3<f32>,
    v: vec3<f32>,
}

// The contact, friction and solver constants (core::step_params::ContactParams,
// layout::Buf::Contact): a uniform block beside the step's, read only by the kernels that
// call these.
@group(0) @binding(37) var<uniform> contact_params: ContactParams;

// Coulomb's coefficients μs and μk (core::step_params::StepParams::mu_static, mu_kinetic).
fn mu_static() -> f32 {
    return contact_params.static_friction;
}

fn mu_kinetic() -> f32 {
    return contact_params.kinetic_friction;
}

// Whether contacts take Coulomb friction instead of the share p.friction
// (StepParams::coulomb).
fn coulomb() -> bool {
    return USES_COULOMB && (mu_static() > 0.0 || mu_kinetic() > 0.0);
}

// VBD's friction coefficient (StepParams::vbd_mu).
fn vbd_mu() -> f32 {
    return select(p.friction, mu_kinetic(), coulomb());
}

// core::cpu::integrate::coulomb_contact: Coulomb friction at a contact of a particle at x
// moving at v with a surface of normal nrm moving at vs, the new (x, v); the tangential
// velocity friction removes moves the position back by it times dt.
fn coulomb_contact(x: vec3<f32>, v: vec3<f32>, vs: vec3<f32>, nrm: vec3<f32>) -> Moved {
    let w = v - vs;
    let vn = dot3(w, nrm);
    let vt = w - vn * nrm;
    let dvn = max(-vn, 0.0);
    let vtl = sqrt(dot3(vt, vt));
    var keep = 0.0;
    if vtl > mu_static() * dvn {
        keep = 1.0 - mu_kinetic() * dvn / vtl;
    }
    let vt2 = vt * keep;
    return Moved(x + (vt2 - vt) * p.dt, vs + vt2 + max(vn, 0.0) * nrm);
}

// core::cpu::integrate::contact (surface_contact: self_collide has its own `contact`): the share's or Coulomb's friction at a contact.
fn surface_contact(x: vec3<f32>, v: vec3<f32>, vs: vec3<f32>, nrm: vec3<f32>) -> Moved {
    if coulomb() {
        return coulomb_contact(x, v, vs, nrm);
    }
    return Moved(x, contact_vel_moving(v, vs, nrm, p.friction));
}

// core::cpu::integrate::grab_vel: the velocity that takes x to the grab's target in dt.
fn grab_vel(x: vec3<f32>) -> vec3<f32> {
    return (p.grab_target.xyz - x) * (1.0 / p.dt);
}

// core::cpu::integrate::integrate_at: the new (x, v) of particle i at x4 (w: inverse mass
// flag) moving at v.
fn integrated(i: u32, x4: vec4<f32>, v: vec3<f32>) -> Moved {
    return integrated_with(i, x4, v, force[world_base + i].xyz);
}

// integrated with the total force f given (the fused forces + integrate kernel).
fn integrated_with(i: u32, x4: vec4<f32>, v: vec3<f32>, f: vec3<f32>) -> Moved {
    let x = x4.xyz;
    if i32(i) == p.grab_index {
        return Moved(p.grab_target.xyz, grab_vel(x));
    }
    if x4.w == 0.0 {
        return Moved(x, vec3<f32>(0.0));
    }
    let vn = v * (1.0 - p.damping) + f * dt_over_mass(x4.w);
    return floor_clamp(x + vn * p.dt, vn);
}

// core::cpu::integrate::floor_clamp: the floor's contact for a particle that moves to x
// with velocity v.
fn floor_clamp(x: vec3<f32>, v: vec3<f32>) -> Moved {
    var xn = x;
    var vn = v;
    let floor = p.floor_y + p.margin;
    if xn.y < floor {
        xn.y = floor;
        if coulomb() {
            return coulomb_contact(xn, vn, vec3<f32>(0.0), vec3<f32>(0.0, 1.0, 0.0));
        }
        vn = contact_vel(vn, vec3<f32>(0.0, 1.0, 0.0), p.friction);
    }
    return Moved(xn, vn);
}

// Whether particle i (w: its pos.w) moves freely: not pinned, not grabbed.
fn is_free(i: u32, w: f32) -> bool {
    return w != 0.0 && i32(i) != p.grab_index;
}

// Whether particle i (w: its pos.w) is held: pinned or grabbed.
fn held(i: u32, w: f32) -> bool {
    return !is_free(i, w);
}

// core::cpu::integrators::accel_dt: a force as the velocity it adds in one substep to a
// particle of pos.w = w.
fn accel_dt(f: vec3<f32>, w: f32) -> vec3<f32> {
    return f * dt_over_mass(w);
}

// core::cpu::integrators::finish_at: the end of a substep for particle i at x4 that
// integrates to x1 with velocity v1 — pins, the grab and the floor as in
// `integrated_with`.
fn finish_at(i: u32, x4: vec4<f32>, x1: vec3<f32>, v1: vec3<f32>) -> Moved {
    let x = x4.xyz;
    if i32(i) == p.grab_index {
        return Moved(p.grab_target.xyz, grab_vel(x));
    }
    if x4.w == 0.0 {
        return Moved(x, vec3<f32>(0.0));
    }
    return floor_clamp(x1, v1);
}
