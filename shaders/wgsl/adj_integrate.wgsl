//! include: state, adjoint
// adj_integrate — per particle: the adjoint of integrate (Verlet in velocity form and the
// floor) and collide's spheres (clothlab_cpu::adjoint::adj_integrate): from the gradient
// with respect to the substep's output position and velocity (planes 0, 1) to the one
// with respect to its input, the force's (plane 2), and the particle's partials of the
// gravity, air drag, damping, friction and particle mass added to planes 3 and 4.
// The still spheres (collide's walk, shared/colliders.wgsl, without the other shapes: a
// scene with them is refused a gradient).
@group(0) @binding(12) var<storage, read> spheres: array<Sphere>;

// sphere_contact's test: the unit normal out of sphere k at x (w: the distance from the
// centre), or w < 0 where x is outside its grown radius.
fn sphere_hit(k: u32, x: vec3<f32>) -> vec4<f32> {
    let s = spheres[k];
    let r = s.radius + p.margin;
    let d = x - s.center;
    let dist2 = dot3(d, d);
    if dist2 >= r * r {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    let dist = sqrt(dist2);
    if dist > 1e-12 {
        return vec4<f32>(d / dist, dist);
    }
    return vec4<f32>(0.0, 1.0, 0.0, dist);
}

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= num_particles() {
        return;
    }
    let x4 = pos[i];
    let w = x4.w;
    if w == 0.0 {
        // Held: x' = x, v' = 0.
        adjoint[adj_at(1u, i)] = vec4<f32>(0.0);
        adjoint[adj_at(2u, i)] = vec4<f32>(0.0);
        return;
    }
    let v = vel[i].xyz;
    let f = force[i].xyz;
    let k = dt_over_mass(w);
    let vt = v * (1.0 - p.damping) + f * k;
    let xt = x4.xyz + vt * p.dt;
    let floor = p.floor_y + p.margin;
    let floored = xt.y < floor;
    var xc = xt;
    var vc = vt;
    if floored {
        xc.y = floor;
        vc = contact_vel(vt, vec3<f32>(0.0, 1.0, 0.0), p.friction);
    }
    var gx = adjoint[adj_at(0u, i)].xyz;
    var gv = adjoint[adj_at(1u, i)].xyz;
    var g_friction = 0.0;
    // The spheres, last first: each one's input found again from the floor's output.
    for (var s = p.num_spheres; s > 0u; s--) {
        var xs = xc;
        var vs = vc;
        for (var q = 0u; q + 1u < s; q++) {
            let h = sphere_hit(q, xs);
            if h.w >= 0.0 {
                vs = contact_vel(vs, h.xyz, p.friction);
                xs = spheres[q].center + h.xyz * (spheres[q].radius + p.margin);
            }
        }
        let h = sphere_hit(s - 1u, xs);
        if h.w < 0.0 {
            continue;
        }
        let n = h.xyz;
        let dist = h.w;
        let r = spheres[s - 1u].radius + p.margin;
        let b = slide_back(vs, n, gv);
        g_friction += b.g_f;
        // at = c + r n, n = d/|d|: ∂n/∂x = (I − n nᵀ)/|d|.
        let gn = b.g_n + gx * r;
        gx = (gn - dot3(n, gn) * n) / max(dist, 1e-12);
        gv = b.g_v;
    }
    if floored {
        gx.y = 0.0;
        let b = slide_back(vt, vec3<f32>(0.0, 1.0, 0.0), gv);
        g_friction += b.g_f;
        gv = b.g_v;
    }
    // x' = x + v' dt; v' = (1 − damping) v + F dt/m; F = f + m g − drag m v.
    let gvt = gv + gx * p.dt;
    let g_f = gvt * k;
    let m = mass_of(w);
    let g = p.gravity.xyz;
    let g_mass = -dot3(gvt, f) * k / p.particle_mass + dot3(g_f, g - p.air_drag * v) / max(w, 1e-30);
    adjoint[adj_at(0u, i)] = vec4<f32>(gx, 0.0);
    adjoint[adj_at(1u, i)] = vec4<f32>(gvt * (1.0 - p.damping) - g_f * (p.air_drag * m), 0.0);
    adjoint[adj_at(2u, i)] = vec4<f32>(g_f, 0.0);
    adjoint[adj_at(3u, i)] += vec4<f32>(g_f * m, -dot3(g_f, v) * m);
    adjoint[adj_at(4u, i)] += vec4<f32>(-dot3(v, gvt), g_friction, g_mass, 0.0);
}
