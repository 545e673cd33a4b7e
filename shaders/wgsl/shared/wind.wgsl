// Wind from face normals, and the bindings of the vertex-normal kernels.

@group(0) @binding(0) var<uniform> step_params: StepParams;
// Copied from step_params by the kernel's first statement (see shared/state.wgsl).
var<private> p: StepParams;
@group(0) @binding(3) var<storage, read_write> force: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> normal: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read> face_slots: array<i32>;
@group(0) @binding(11) var<storage, read_write> faces: array<vec4<f32>>;

// Whether there is wind at all (no wind adds exact zeros: the division is skipped).
fn windy() -> bool {
    return p.wind.w / 6.0 != 0.0 && any(p.wind.xyz != vec3<f32>(0.0));
}

// Wind force of one adjacent face f4 (N, |N|) on a particle: a third of c (N.w) N / (2 |N|)
// (core::cpu::normals::vnormal_at).
fn face_wind(f4: vec4<f32>) -> vec3<f32> {
    let c = p.wind.w / 6.0;
    if f4.w > 0.0 {
        return f4.xyz * (c * dot(f4.xyz, p.wind.xyz) / f4.w);
    }
    return vec3<f32>(0.0);
}

// Wind force on particle i from its adjacent faces, in slot order.
fn wind_at(i: u32) -> vec3<f32> {
    var wind = vec3<f32>(0.0);
    if !windy() {
        return wind;
    }
    for (var s = 0u; s < FACE_SLOTS; s++) {
        let t = face_slots[i * FACE_SLOTS + s];
        if t >= 0 {
            wind += face_wind(faces[u32(t)]);
        }
    }
    return wind;
}
