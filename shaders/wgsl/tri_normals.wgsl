//! worlds
// tri_normals — area-weighted face normals, |N| in w (optimized variant): one invocation per
// quad computes both its triangles from its four corners, numbered as core::grid::build
// numbers them (triangles 2q = (p00, p01, p11) and 2q + 1 = (p00, p11, p10) of quad
// q = qj (n - 1) + qi): four position loads for two faces instead of six plus six
// index loads. A mesh (n = 0) has no quads: invocation q computes triangles 2q and
// 2q + 1 of the triangle list from their corners' indices.
@group(0) @binding(0) var<uniform> step_params: StepParams;
// Copied from step_params by the kernel's first statement (see shared/state.wgsl).
var<private> p: StepParams;
@group(0) @binding(1) var<storage, read_write> pos: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read> triangles: array<u32>;
@group(0) @binding(11) var<storage, read_write> faces: array<vec4<f32>>;

// Face t of the triangle list (core::cpu::normals::tri_normals).
fn list_face(t: u32) {
    let a = pos[world_base + triangles[3u * t]].xyz;
    let b = pos[world_base + triangles[3u * t + 1u]].xyz;
    let c = pos[world_base + triangles[3u * t + 2u]].xyz;
    let nrm = cross(b - a, c - a);
    faces[face_base + t] = vec4<f32>(nrm, len3(nrm));
}

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let q = flat_id(id, groups);
    if p.n == 0u {
        let count = arrayLength(&triangles) / 3u;
        for (var t = 2u * q; t < min(2u * q + 2u, count); t++) {
            list_face(t);
        }
        return;
    }
    let m = p.n - 1u;
    if q >= m * m {
        return;
    }
    let qj = q / m;
    let p00 = qj * p.n + q - qj * m;
    let x00 = pos[world_base + p00].xyz;
    let x10 = pos[world_base + p00 + 1u].xyz;
    let x01 = pos[world_base + p00 + p.n].xyz;
    let x11 = pos[world_base + p00 + p.n + 1u].xyz;
    let n0 = cross(x01 - x00, x11 - x00);
    let n1 = cross(x11 - x00, x10 - x00);
    faces[face_base + 2u * q] = vec4<f32>(n0, len3(n0));
    faces[face_base + 2u * q + 1u] = vec4<f32>(n1, len3(n1));
}
