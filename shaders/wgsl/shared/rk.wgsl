// One Runge–Kutta stage (core::cpu::integrators::rk_stage): the stage's force is in the
// force buffer; its (v, a·dt) weighted by b is added to the sums in aux2, aux3 (started by
// the first stage); then the particles go to the next stage's point y₀ + c_next·dt·k (the
// saved wind back in the force buffer), or the last stage ends the substep at
// y₀ + dt Σ bₛkₛ.
fn rk_stage(i: u32, c_next: f32, b: f32, first: bool, last: bool) {
    let x4 = pos[world_base + i];
    let us = vel[world_base + i].xyz;
    let gs = accel_dt(force[world_base + i].xyz, x4.w);
    var sx = us * b;
    var su = gs * b;
    if !first {
        sx = aux2[world_base + i].xyz + us * b;
        su = aux3[world_base + i].xyz + gs * b;
    }
    let x0 = aux0[world_base + i].xyz;
    let v0 = aux1[world_base + i].xyz;
    aux2[world_base + i] = vec4<f32>(sx, 0.0);
    aux3[world_base + i] = vec4<f32>(su, 0.0);
    if last {
        let m = finish_at(i, x4, x0 + sx * p.dt, v0 + su);
        vel[world_base + i] = vec4<f32>(m.v, 0.0);
        pos[world_base + i] = vec4<f32>(m.x, x4.w);
        return;
    }
    force[world_base + i] = aux4[world_base + i];
    if held(i, x4.w) {
        vel[world_base + i] = vec4<f32>(0.0);
        return;
    }
    pos[world_base + i] = vec4<f32>(x0 + us * (c_next * p.dt), x4.w);
    vel[world_base + i] = vec4<f32>(v0 + gs * c_next, 0.0);
}
