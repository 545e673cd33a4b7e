//! include: state, table
// xpbd — one XPBD pass per particle, Jacobi with averaging (core::cpu::integrators::xpbd):
// every spring with ks > 0 a distance constraint of compliance 1/(ks dt²) and damping
// kd/(ks dt), λ = 0 (one pass per substep); reads pos (predicted) and prev (where the
// substep began), writes pos_out.
@group(0) @binding(5) var<storage, read_write> pos_out: array<vec4<f32>>;

fn mobility(k: u32, w: f32) -> f32 {
    if i32(k) == p.grab_index {
        return 0.0;
    }
    return w;
}

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let x4 = pos[i];
    let wi = mobility(i, x4.w);
    if wi == 0.0 {
        pos_out[i] = x4;
        return;
    }
    let inv_m = 1.0 / p.particle_mass;
    let xi = x4.xyz;
    let ui = xi - prev[i].xyz;
    var corr = vec3<f32>(0.0);
    var count = 0.0;
    for (var s = 0u; s < SLOTS; s++) {
        let slot = slot_at(i, s);
        if slot.neighbor < 0 || slot.ks <= 0.0 {
            continue;
        }
        let b = u32(slot.neighbor);
        let xb4 = pos[b];
        let d = xi - xb4.xyz;
        let len = length(d);
        if len <= 1.17549435e-38 {
            continue;
        }
        let n = d * (1.0 / len);
        let alpha = 1.0 / (slot.ks * p.dt * p.dt);
        let gamma = slot.kd / (slot.ks * p.dt);
        let wb = mobility(b, xb4.w);
        let rel = dot(n, ui - (xb4.xyz - prev[b].xyz));
        let dl = -((len - slot.rest) + gamma * rel) / ((1.0 + gamma) * (wi + wb) * inv_m + alpha);
        corr += n * (dl * wi * inv_m);
        count += 1.0;
    }
    if count > 0.0 {
        pos_out[i] = vec4<f32>(xi + corr / count, x4.w);
    } else {
        pos_out[i] = x4;
    }
}
