// One Runge–Kutta stage (core::cpu::integrators::rk_stage): the stage's force is in the
// force buffer; its (u, g) weighted by b is added to the sums in aux2, aux3 (started by
// the first stage); then the particles go to the next stage's point x₀ + c_next·k (the
// velocity in prev, the saved wind back in the force buffer), or the last stage ends the
// substep at y₀ + Σ bₛkₛ.
fn rk_stage(i: u32, c_next: f32, b: f32, first: bool, last: bool) {
    let x4 = pos[i];
    // The first stage evaluates at y₀: its u is the saved one, exactly.
    var us = x4.xyz - prev[i].xyz;
    if first {
        us = aux1[i].xyz;
    }
    let gs = accel_dt2(force[i].xyz);
    var sx = us * b;
    var su = gs * b;
    if !first {
        sx = aux2[i].xyz + us * b;
        su = aux3[i].xyz + gs * b;
    }
    let x0 = aux0[i].xyz;
    let u0 = aux1[i].xyz;
    aux2[i] = vec4<f32>(sx, 0.0);
    aux3[i] = vec4<f32>(su, 0.0);
    if last {
        let m = finish_at(i, x4, x0 + sx, u0 + su);
        prev[i] = vec4<f32>(m.xp, 0.0);
        pos[i] = vec4<f32>(m.x, x4.w);
        return;
    }
    force[i] = aux4[i];
    if held(i, x4.w) {
        prev[i] = vec4<f32>(x4.xyz, 0.0);
        return;
    }
    let x = x0 + us * c_next;
    let u = u0 + gs * c_next;
    pos[i] = vec4<f32>(x, x4.w);
    prev[i] = vec4<f32>(x - u, 0.0);
}
