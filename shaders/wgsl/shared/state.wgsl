// The particle state and the per-particle kernels that touch only their own particle.

@group(0) @binding(0) var<uniform> p: StepParams;
@group(0) @binding(1) var<storage, read_write> pos: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> prev: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> force: array<vec4<f32>>;

fn num_particles() -> u32 {
    return p.n * p.n;
}

// core::cpu::forces::forces_at: f + m g - drag (x - x*).
fn forces_at(i: u32, f: vec4<f32>) -> vec4<f32> {
    let g = p.gravity.xyz * p.particle_mass;
    let drag = p.air_drag * p.particle_mass / p.dt;
    let v_dt = pos[i].xyz - prev[i].xyz;
    return vec4<f32>(f.xyz + g - v_dt * drag, 0.0);
}

// core::cpu::integrate::integrate_at, in place.
fn integrate_at(i: u32) {
    let x4 = pos[i];
    let w = x4.w;
    let x = x4.xyz;
    if i32(i) == p.grab_index {
        prev[i] = vec4<f32>(x, 0.0);
        pos[i] = vec4<f32>(p.grab_target.xyz, w);
        return;
    }
    if w == 0.0 {
        prev[i] = vec4<f32>(x, 0.0);
        return;
    }
    var xn = x + (x - prev[i].xyz) * (1.0 - p.damping) + force[i].xyz * (p.dt * p.dt / p.particle_mass);
    var xp = x;
    let floor = p.floor_y + p.margin;
    if xn.y < floor {
        xn.y = floor;
        xp = contact_prev(xn, xp, vec3<f32>(0.0, 1.0, 0.0), p.friction);
    }
    prev[i] = vec4<f32>(xp, 0.0);
    pos[i] = vec4<f32>(xn, w);
}
