//! include: wind
// vertex_normals — per particle: sum of the adjacent face normals (gathered in slot order),
// normalised, and the wind force into the force buffer (optimized variant).
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = flat_id(id, groups);
    if i >= p.n * p.n {
        return;
    }
    var sum = vec3<f32>(0.0);
    for (var s = 0u; s < FACE_SLOTS; s++) {
        let t = face_slots[i * FACE_SLOTS + s];
        if t >= 0 {
            sum += faces[u32(t)].xyz;
        }
    }
    normal[i] = vec4<f32>(normalize_or_zero(sum), 0.0);
    force[i] = vec4<f32>(wind_at(i), 0.0);
}
