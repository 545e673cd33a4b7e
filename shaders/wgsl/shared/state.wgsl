// The particle state and the per-particle kernels that touch only their own particle.

@group(0) @binding(0) var<uniform> step_params: StepParams;
// The step constants, copied from the uniform block (immediates in the `_imm` twins) by
// the first statement of every kernel, outside all control flow: llvmpipe reads uniforms
// as scalars only where every invocation is known to be active, and gathers them lane by
// lane inside any branch (including the one an early `return` opens).
var<private> p: StepParams;
@group(0) @binding(1) var<storage, read_write> pos: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> prev: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> force: array<vec4<f32>>;

fn num_particles() -> u32 {
    return p.n * p.n;
}

// core::cpu::forces::forces_at: f + m g - drag (x - x*), with v_dt = x - x* of the particle
// (passed in, so that a kernel that needs x and x* again loads them once).
fn forces_at(f: vec4<f32>, v_dt: vec3<f32>) -> vec4<f32> {
    let g = p.gravity.xyz * p.particle_mass;
    let drag = p.air_drag * p.particle_mass / p.dt;
    return vec4<f32>(f.xyz + g - v_dt * drag, 0.0);
}

// A particle's position and previous position. The per-particle kernels load each once
// and store each once: on drivers that emulate storage-buffer access lane by lane
// (llvmpipe) every access counts.
struct Moved {
    x: vec3<f32>,
    xp: vec3<f32>,
}

// core::cpu::integrate::integrate_at: the new (x, x*) of particle i at x4 (w: inverse mass
// flag) with previous position xp.
fn integrated(i: u32, x4: vec4<f32>, xp: vec3<f32>) -> Moved {
    return integrated_with(i, x4, xp, force[i].xyz);
}

// integrated with the total force f given (the fused forces + integrate kernel).
fn integrated_with(i: u32, x4: vec4<f32>, xp: vec3<f32>, f: vec3<f32>) -> Moved {
    let x = x4.xyz;
    if i32(i) == p.grab_index {
        return Moved(p.grab_target.xyz, x);
    }
    if x4.w == 0.0 {
        return Moved(x, x);
    }
    var xn = x + (x - xp) * (1.0 - p.damping) + f * (p.dt * p.dt / p.particle_mass);
    var xq = x;
    let floor = p.floor_y + p.margin;
    if xn.y < floor {
        xn.y = floor;
        xq = contact_prev(xn, xq, vec3<f32>(0.0, 1.0, 0.0), p.friction);
    }
    return Moved(xn, xq);
}

// Whether particle i (w: its pos.w) moves freely: not pinned, not grabbed.
fn is_free(i: u32, w: f32) -> bool {
    return w != 0.0 && i32(i) != p.grab_index;
}

// Whether particle i (w: its pos.w) is held: pinned or grabbed.
fn held(i: u32, w: f32) -> bool {
    return !is_free(i, w);
}

// core::cpu::integrators::accel_dt2: a force as the displacement it adds in one substep.
fn accel_dt2(f: vec3<f32>) -> vec3<f32> {
    return f * (p.dt * p.dt / p.particle_mass);
}

// core::cpu::integrators::finish_at: the end of a substep for particle i at x4 that
// integrates to x1 with velocity displacement u1 — pins, the grab and the floor as in
// `integrated_with`.
fn finish_at(i: u32, x4: vec4<f32>, x1: vec3<f32>, u1: vec3<f32>) -> Moved {
    let x = x4.xyz;
    if i32(i) == p.grab_index {
        return Moved(p.grab_target.xyz, x);
    }
    if x4.w == 0.0 {
        return Moved(x, x);
    }
    var xn = x1;
    var xp = x1 - u1;
    let floor = p.floor_y + p.margin;
    if xn.y < floor {
        xn.y = floor;
        xp = contact_prev(xn, xp, vec3<f32>(0.0, 1.0, 0.0), p.friction);
    }
    return Moved(xn, xp);
}
