// Wind from face normals, and the bindings of the vertex-normal kernels.

@group(0) @binding(0) var<uniform> p: StepParams;
@group(0) @binding(3) var<storage, read_write> force: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> normal: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read> face_slots: array<i32>;
@group(0) @binding(11) var<storage, read_write> faces: array<vec4<f32>>;

// Wind force on particle i: a third of c (N.w) N / (2 |N|) per adjacent face
// (core::cpu::normals::vnormal_at).
fn wind_at(i: u32) -> vec3<f32> {
    let w = p.wind.xyz;
    let c = p.wind.w / 6.0;
    var wind = vec3<f32>(0.0);
    if c == 0.0 || all(w == vec3<f32>(0.0)) {
        return wind;
    }
    for (var s = 0u; s < FACE_SLOTS; s++) {
        let t = face_slots[i * FACE_SLOTS + s];
        if t < 0 {
            continue;
        }
        let f4 = faces[u32(t)];
        if f4.w > 0.0 {
            wind += f4.xyz * (c * dot(f4.xyz, w) / f4.w);
        }
    }
    return wind;
}
