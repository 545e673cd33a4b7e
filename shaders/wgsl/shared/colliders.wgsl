// Sphere and box colliders (needs state.wgsl). The build also emits every kernel that
// includes this file as `<kernel>_cu`, with these two declarations swapped for uniform
// blocks of MAX_COLLIDERS entries (the thesis's constant memory: `colliders=uniform`).

@group(0) @binding(12) var<storage, read> spheres: array<Sphere>;
@group(0) @binding(13) var<storage, read> boxes: array<Aabb>;

// core::cpu::collide::collide_at for a free particle (is_free): m pushed out of the
// spheres and boxes, its velocity relative to their surfaces where they move.
fn collided(m: Moved) -> Moved {
    var x = m.x;
    var v = m.v;
    for (var k = 0u; k < p.num_spheres; k++) {
        let s = spheres[k];
        let r = s.radius + p.margin;
        let d = x - s.center;
        let dist2 = dot3(d, d);
        if dist2 < r * r {
            let dist = sqrt(dist2);
            var nrm = vec3<f32>(0.0, 1.0, 0.0);
            if dist > 1e-12 {
                nrm = d / dist;
            }
            let arm = nrm * r;
            x = s.center + arm;
            let vs = surface_vel(s.velocity.xyz, s.spin.xyz, arm);
            v = contact_vel_moving(v, vs, nrm, p.friction);
        }
    }
    for (var k = 0u; k < p.num_boxes; k++) {
        let lo = boxes[k].min.xyz - vec3<f32>(p.margin);
        let hi = boxes[k].max.xyz + vec3<f32>(p.margin);
        if all(x > lo) && all(x < hi) {
            let below = x - lo;
            let above = hi - x;
            var best = below.x;
            var nrm = vec3<f32>(-1.0, 0.0, 0.0);
            var face = lo.x;
            if above.x < best { best = above.x; nrm = vec3<f32>(1.0, 0.0, 0.0); face = hi.x; }
            if below.y < best { best = below.y; nrm = vec3<f32>(0.0, -1.0, 0.0); face = lo.y; }
            if above.y < best { best = above.y; nrm = vec3<f32>(0.0, 1.0, 0.0); face = hi.y; }
            if below.z < best { best = below.z; nrm = vec3<f32>(0.0, 0.0, -1.0); face = lo.z; }
            if above.z < best { best = above.z; nrm = vec3<f32>(0.0, 0.0, 1.0); face = hi.z; }
            let axis = abs(nrm);
            x = x * (vec3<f32>(1.0) - axis) + axis * face;
            v = contact_vel_moving(v, boxes[k].velocity.xyz, nrm, p.friction);
        }
    }
    return Moved(x, v);
}
