// One XPBD pass (core::cpu::integrators::xpbd_pass): the springs in slot s of the
// particles of one colour — no two share a particle — each a distance constraint of
// compliance 1/(ks dt²) and damping kd/(ks dt), its λ kept in component c of aux0 (buf 0)
// or aux1 (buf 1) at its first end, solved for both ends by their mobilities, in place;
// each end's velocity gains its correction over dt (so that v·dt stays its displacement
// since the substep began, which the damping term reads).

fn mobility(k: u32, w: f32) -> f32 {
    if i32(k) == p.grab_index {
        return 0.0;
    }
    return w;
}

// core::cpu::integrators::xpbd_colour.
fn xpbd_colour(di: i32, dj: i32, i: u32, j: u32) -> u32 {
    if di != 0 {
        return (i / u32(abs(di))) % 2u;
    }
    return (j / u32(abs(dj))) % 2u;
}

fn lambda_at(a: u32, buf: u32, c: u32) -> f32 {
    if buf == 0u {
        return aux0[a][c];
    }
    return aux1[a][c];
}

fn set_lambda(a: u32, buf: u32, c: u32, l: f32) {
    if buf == 0u {
        aux0[a][c] = l;
    } else {
        aux1[a][c] = l;
    }
}

fn xpbd_pass(a: u32, s: u32, di: i32, dj: i32, colour: u32, buf: u32, c: u32) {
    if xpbd_colour(di, dj, a % p.n, a / p.n) != colour {
        return;
    }
    let slot = slot_at(a, s);
    if slot.neighbor < 0 || slot.ks <= 0.0 {
        return;
    }
    let b = u32(slot.neighbor);
    let xa4 = pos[a];
    let xb4 = pos[b];
    let inv_m = 1.0 / p.particle_mass;
    let wa = mobility(a, xa4.w) * inv_m;
    let wb = mobility(b, xb4.w) * inv_m;
    if wa + wb == 0.0 {
        return;
    }
    let d = xa4.xyz - xb4.xyz;
    let len = len3(d);
    if len <= 1.17549435e-38 {
        return;
    }
    let n = d * (1.0 / len);
    let alpha = 1.0 / (slot.ks * p.dt * p.dt);
    let gamma = slot.kd / (slot.ks * p.dt);
    let va = vel[a].xyz;
    let vb = vel[b].xyz;
    let rel = dot3(n, va - vb) * p.dt;
    let l = lambda_at(a, buf, c);
    let dl = -((len - slot.rest) + alpha * l + gamma * rel) / ((1.0 + gamma) * (wa + wb) + alpha);
    let da = n * (dl * wa);
    let db = n * (dl * wb);
    let inv_dt = 1.0 / p.dt;
    pos[a] = vec4<f32>(xa4.xyz + da, xa4.w);
    pos[b] = vec4<f32>(xb4.xyz - db, xb4.w);
    vel[a] = vec4<f32>(va + da * inv_dt, 0.0);
    vel[b] = vec4<f32>(vb - db * inv_dt, 0.0);
    set_lambda(a, buf, c, l + dl);
}
