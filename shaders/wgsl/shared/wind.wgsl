// The bindings of the vertex-normal kernels, and their faces for shared/wind_fn.wgsl.

@group(0) @binding(0) var<uniform> step_params: StepParams;
// Copied from step_params by the kernel's first statement (see shared/state.wgsl).
var<private> p: StepParams;
@group(0) @binding(3) var<storage, read_write> force: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> normal: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read> face_slots: array<i32>;
@group(0) @binding(11) var<storage, read_write> faces: array<vec4<f32>>;

// Face t, as tri_normals stored it (for wind_at, shared/wind_fn.wgsl).
fn face_at(t: u32) -> vec4<f32> {
    return faces[face_base + t];
}
