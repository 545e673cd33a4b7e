// XPBD's distance constraint (core::cpu::integrators::xpbd_solve), for a grid's passes
// (shared/xpbd_grid.wgsl) and a mesh's (xpbd_mesh.wgsl): a spring of compliance
// 1/(ks dt²) and damping kd/(ks dt) solved for both ends by their mobilities, in place;
// each end's velocity gains its correction over dt (so that v·dt stays its displacement
// since the substep began, which the damping term reads).

fn mobility(k: u32, w: f32) -> f32 {
    if i32(k) == p.grab_index {
        return 0.0;
    }
    return w;
}

// What xpbd_solve did: whether it moved the ends, and λ's increment.
struct Solved {
    moved: bool,
    dl: f32,
}

// core::cpu::integrators::xpbd_solve: the constraint of `slot` between a and b with
// multiplier l, both ends (and their velocities) moved in place; nothing when neither
// moves.
fn xpbd_solve(a: u32, b: u32, slot: SpringSlot, l: f32) -> Solved {
    let xa4 = pos[world_base + a];
    let xb4 = pos[world_base + b];
    // w / m̄ as one division, as the twin computes it (w · (1 / m̄) rounds twice, and a
    // compiler allowed reciprocals may rewrite one into the other).
    let wa = mobility(a, xa4.w) / p.particle_mass;
    let wb = mobility(b, xb4.w) / p.particle_mass;
    if wa + wb == 0.0 {
        return Solved(false, 0.0);
    }
    let d = xa4.xyz - xb4.xyz;
    let len = len3(d);
    if len <= 1.17549435e-38 {
        return Solved(false, 0.0);
    }
    let n = d * (1.0 / len);
    let alpha = 1.0 / (slot.ks * p.dt * p.dt);
    let gamma = slot.kd / (slot.ks * p.dt);
    let va = vel[world_base + a].xyz;
    let vb = vel[world_base + b].xyz;
    let rel = dot3(n, va - vb) * p.dt;
    let dl = -((len - slot.rest) + alpha * l + gamma * rel) / ((1.0 + gamma) * (wa + wb) + alpha);
    let da = n * (dl * wa);
    let db = n * (dl * wb);
    let inv_dt = 1.0 / p.dt;
    pos[world_base + a] = vec4<f32>(xa4.xyz + da, xa4.w);
    pos[world_base + b] = vec4<f32>(xb4.xyz - db, xb4.w);
    vel[world_base + a] = vec4<f32>(va + da * inv_dt, 0.0);
    vel[world_base + b] = vec4<f32>(vb - db * inv_dt, 0.0);
    return Solved(true, dl);
}
