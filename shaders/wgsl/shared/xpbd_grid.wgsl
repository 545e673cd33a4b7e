// One XPBD pass of a grid (core::cpu::integrators::xpbd_pass; needs shared/xpbd.wgsl):
// the springs in slot s of the particles of one colour — no two share a particle — its λ
// kept in component c of aux0 (buf 0) or aux1 (buf 1) at its first end.

// core::cpu::integrators::xpbd_colour.
fn xpbd_colour(di: i32, dj: i32, i: u32, j: u32) -> u32 {
    if di != 0 {
        return (i / u32(abs(di))) % 2u;
    }
    return (j / u32(abs(dj))) % 2u;
}

fn lambda_at(a: u32, buf: u32, c: u32) -> f32 {
    if buf == 0u {
        return aux0[world_base + a][c];
    }
    return aux1[world_base + a][c];
}

fn set_lambda(a: u32, buf: u32, c: u32, l: f32) {
    if buf == 0u {
        aux0[world_base + a][c] = l;
    } else {
        aux1[world_base + a][c] = l;
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
    let l = lambda_at(a, buf, c);
    let r = xpbd_solve(a, u32(slot.neighbor), slot, l);
    if r.moved {
        set_lambda(a, buf, c, l + r.dl);
    }
}
