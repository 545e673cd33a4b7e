// The bindings of the vertex-normal kernels, and the wind of a particle's stored faces
// (with shared/wind_fn.wgsl).

@group(0) @binding(0) var<uniform> step_params: StepParams;
// Copied from step_params by the kernel's first statement (see shared/state.wgsl).
var<private> p: StepParams;
@group(0) @binding(3) var<storage, read_write> force: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> normal: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read> face_slots: array<i32>;
@group(0) @binding(11) var<storage, read_write> faces: array<vec4<f32>>;

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
