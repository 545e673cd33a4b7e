//! include: state, table, adjacency, adjoint
//! no table image
// adj_springs — per particle: the adjoint of the spring gather (clothlab_cpu::adjoint::
// adj_springs). Each slot's spring taken back onto this end: Jᵀ (ḡ_a − ḡ_b) added to the
// position's gradient and the velocity's (ḡ: plane 2, the force's gradient), each spring's
// partials of its stiffness and damping counted at its lower end, by kind (planes 5, 6, 7:
// Σ ∂/∂ks, Σ ∂/∂kd, Σ ks ∂/∂ks, Σ kd ∂/∂kd). It reads the table from its storage
// buffers on every solver (no `_tex` twin).
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let xa = pos[i].xyz;
    let va = vel[i].xyz;
    let ga = adjoint[adj_at(2u, i)].xyz;
    var gx = vec3<f32>(0.0);
    var gv = vec3<f32>(0.0);
    var part = array<vec4<f32>, 3>(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    let r = slot_row(i);
    for (var s = 0u; s < r.count; s++) {
        let slot = row_slot(i, r, s);
        let other = slot_other(slot);
        if other < 0 {
            continue;
        }
        let b = u32(other);
        let l = xa - pos[b].xyz;
        let len = len3(l);
        if len <= 1.17549435e-38 {
            continue;
        }
        let dir = l * (1.0 / len);
        let dv = va - vel[b].xyz;
        let fb = ga - adjoint[adj_at(2u, b)].xyz;
        let stretch = len - slot.rest;
        let rate = dot3(dv, dir);
        let sc = slot.ks * stretch + slot.kd * rate;
        let along = dot3(dir, fb);
        gx += -along * (slot.ks * dir + slot.kd * (dv - rate * dir) / len) - (sc / len) * (fb - along * dir);
        gv += (-slot.kd * along) * dir;
        if i < b {
            // A grid's slots by family (4 each), a mesh's edges then bending springs.
            var kind = s / 4u;
            if p.n == 0u {
                kind = select(2u, 0u, s < r.head);
            }
            let gks = -stretch * along;
            let gkd = -rate * along;
            part[kind] += vec4<f32>(gks, gkd, gks * slot.ks, gkd * slot.kd);
        }
    }
    adjoint[adj_at(0u, i)] += vec4<f32>(gx, 0.0);
    adjoint[adj_at(1u, i)] += vec4<f32>(gv, 0.0);
    adjoint[adj_at(5u, i)] += part[0];
    adjoint[adj_at(6u, i)] += part[1];
    adjoint[adj_at(7u, i)] += part[2];
}
