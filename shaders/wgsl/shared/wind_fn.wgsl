// Wind from face normals, for shared/wind.wgsl's kernels (faces stored by tri_normals)
// and the forces gather that computes its faces itself (shared/face_wind.wgsl). No
// bindings of its own: `wind_at` walks the includer's `face_slots` and asks the includer's
// `face_at(t)` for each face.

// Whether there is wind at all (no wind adds exact zeros: the division is skipped).
fn windy() -> bool {
    return p.wind.w / 6.0 != 0.0 && any(p.wind.xyz != vec3<f32>(0.0));
}

// Wind force of one adjacent face f4 (N, |N|) on a particle: a third of c (N.w) N / (2 |N|)
// (core::cpu::normals::vnormal_at).
fn face_wind(f4: vec4<f32>) -> vec3<f32> {
    let c = p.wind.w / 6.0;
    if f4.w > 0.0 {
        return f4.xyz * (c * dot3(f4.xyz, p.wind.xyz) / f4.w);
    }
    return vec3<f32>(0.0);
}

// Wind force on particle i from its adjacent faces, in slot order
// (core::cpu::normals::vnormal_at).
fn wind_at(i: u32) -> vec3<f32> {
    var wind = vec3<f32>(0.0);
    if !windy() {
        return wind;
    }
    let r = face_row(i);
    for (var s = 0u; s < r.count; s++) {
        let t = face_slots[r.first + s];
        if t >= 0 {
            wind += face_wind(face_at(u32(t)));
        }
    }
    return wind;
}
