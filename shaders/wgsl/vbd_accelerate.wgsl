//! include: state, aux, range
//! worlds
// vbd_accelerate — the paper's Chebyshev acceleration after a VBD sweep
// (core::cpu::vbd::vbd_accelerate): D ← ω (D − D⁽ᵏ⁻²⁾) + D⁽ᵏ⁻²⁾ per free particle, the sweeps'
// last two results in aux3 (the last) and aux4 (the one before); after the first sweep
// (ω = 1) D is kept and the two set up, the one before being the prediction's h v'
// (aux0). ω comes in the immediates as the bits of `first` (one dispatch per sweep, over
// `count` = every particle).

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let range = pass_range;
    let i = flat_id(id, groups);
    if i >= range.count || i >= num_particles() {
        return;
    }
    let omega = bitcast<f32>(range.first);
    let d = aux2[world_base + i].xyz;
    var acc = d;
    var last = d;
    var before = d;
    if !held(i, aux1[world_base + i].w) {
        if omega == 1.0 {
            before = aux0[world_base + i].xyz * p.dt;
        } else {
            before = aux4[world_base + i].xyz;
            acc = (d - before) * omega + before;
            last = acc;
            before = aux3[world_base + i].xyz;
        }
    }
    aux2[world_base + i] = vec4<f32>(acc, 0.0);
    aux3[world_base + i] = vec4<f32>(last, 0.0);
    aux4[world_base + i] = vec4<f32>(before, 0.0);
}
