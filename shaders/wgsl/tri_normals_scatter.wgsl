//! include: atomic_cas
//! worlds
// tri_normals — per triangle (naive variant): the face normal, also added to its three
// corners' normal accumulators with atomics.
@group(0) @binding(0) var<uniform> step_params: StepParams;
// Copied from step_params by the kernel's first statement (see shared/state.wgsl).
var<private> p: StepParams;
@group(0) @binding(1) var<storage, read_write> pos: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> accum: array<AtomicF32>;
@group(0) @binding(9) var<storage, read> triangles: array<u32>;
@group(0) @binding(11) var<storage, read_write> faces: array<vec4<f32>>;

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let t = flat_id(id, groups);
    if t >= arrayLength(&triangles) / 3u {
        return;
    }
    // (A batch's world: its particles from world_base, its faces from face_base.)
    let ia = world_base + triangles[3u * t];
    let ib = world_base + triangles[3u * t + 1u];
    let ic = world_base + triangles[3u * t + 2u];
    let xa = pos[ia].xyz;
    let nrm = cross(pos[ib].xyz - xa, pos[ic].xyz - xa);
    faces[face_base + t] = vec4<f32>(nrm, len3(nrm));
    for (var c = 0u; c < 3u; c++) {
        atomic_add_f32(4u * ia + c, nrm[c]);
        atomic_add_f32(4u * ib + c, nrm[c]);
        atomic_add_f32(4u * ic + c, nrm[c]);
    }
}
