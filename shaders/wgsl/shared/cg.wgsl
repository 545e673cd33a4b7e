// Implicit Euler's matrix A = m(1 + dt·drag) I + Σₛ (dt² Kₛ + dt Dₛ), applied matrix-free
// over a particle's slots (core::cpu::integrators::apply_at).

struct Applied {
    v: vec3<f32>,
    diag: f32,
}

// The vector A (or dt² K) is applied to, at particle k: p (aux2) or the velocity v.
fn y_at(k: u32, from_p: bool) -> vec3<f32> {
    if from_p {
        return aux2[world_base + k].xyz;
    }
    return vel[world_base + k].xyz;
}

// (dt² Kₛ + dt Dₛ) y (without Dₛ unless with_damping) for the spring from xa to xb, and a
// third of the trace of dt² Kₛ + dt Dₛ.
fn spring_block(s: SpringSlot, xa: vec3<f32>, xb: vec3<f32>, y: vec3<f32>, with_damping: bool) -> Applied {
    let d = xa - xb;
    let len = len3(d);
    if len <= 1.17549435e-38 {
        return Applied(vec3<f32>(0.0), 0.0);
    }
    let n = d * (1.0 / len);
    let soft = max(1.0 - s.rest / len, 0.0);
    let ny = dot3(n, y);
    let k2 = s.ks * p.dt * p.dt;
    var c = 0.0;
    if with_damping {
        c = s.kd * p.dt;
    }
    let v = n * ((k2 + c) * ny) + (y - n * ny) * (k2 * soft);
    return Applied(v, (k2 * (1.0 + 2.0 * soft) + s.kd * p.dt) / 3.0);
}

// (A y)ᵢ with y = p (full), or dt² (K v)ᵢ (not full); and the diagonal of A.
fn apply_at(i: u32, full: bool) -> Applied {
    let xa4 = pos[world_base + i];
    let xa = xa4.xyz;
    let ya = y_at(i, full);
    let m = mass_of(xa4.w) * (1.0 + p.dt * p.air_drag);
    var acc = vec3<f32>(0.0);
    if full {
        acc = ya * m;
    }
    var diag = m;
    let r = slot_row(i);
    for (var s = 0u; s < r.count; s++) {
        let slot = row_slot(i, r, s);
        let other = slot_other(slot);
        if other < 0 {
            continue;
        }
        let b = u32(other);
        let blk = spring_block(slot, xa, pos[world_base + b].xyz, ya - y_at(b, full), full);
        acc += blk.v;
        diag += blk.diag;
    }
    return Applied(acc, diag);
}
