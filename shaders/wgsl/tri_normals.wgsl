// tri_normals — per triangle: area-weighted face normal, |N| in w.
@group(0) @binding(0) var<uniform> step_params: StepParams;
// Copied from step_params by the kernel's first statement (see shared/state.wgsl).
var<private> p: StepParams;
@group(0) @binding(1) var<storage, read_write> pos: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read> triangles: array<u32>;
@group(0) @binding(11) var<storage, read_write> faces: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let t = flat_id(id, groups);
    if t >= arrayLength(&faces) {
        return;
    }
    let xa = pos[triangles[3u * t]].xyz;
    let xb = pos[triangles[3u * t + 1u]].xyz;
    let xc = pos[triangles[3u * t + 2u]].xyz;
    let nrm = cross(xb - xa, xc - xa);
    faces[t] = vec4<f32>(nrm, length(nrm));
}
