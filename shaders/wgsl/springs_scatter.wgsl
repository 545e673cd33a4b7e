//! include: atomic_cas
//! worlds
// springs — per spring: add the force to both ends with atomics (naive variant).
@group(0) @binding(0) var<uniform> step_params: StepParams;
// Copied from step_params by the kernel's first statement (see shared/state.wgsl).
var<private> p: StepParams;
@group(0) @binding(1) var<storage, read_write> pos: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> vel: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> accum: array<AtomicF32>;
// The spring list in two halves, each within the 128 MiB a storage binding may span on
// many adapters up to n = 1024.
@group(0) @binding(7) var<storage, read> springs: array<Spring>;
@group(0) @binding(15) var<storage, read> springs_b: array<Spring>;

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let k = flat_id(id, groups);
    let half = arrayLength(&springs);
    if k >= half + arrayLength(&springs_b) {
        return;
    }
    var s: Spring;
    if k < half {
        s = springs[k];
    } else {
        s = springs_b[k - half];
    }
    // (A batch's world: its particles from world_base; the springs are every world's.)
    let a = world_base + s.a;
    let b = world_base + s.b;
    let xa = pos[a].xyz;
    let xb = pos[b].xyz;
    let va = vel[a].xyz;
    let vb = vel[b].xyz;
    let fa = spring_force(xa - xb, va - vb, SpringSlot(i32(s.b), s.rest, s.ks, s.kd));
    for (var c = 0u; c < 3u; c++) {
        atomic_add_f32(4u * a + c, fa[c]);
        atomic_add_f32(4u * b + c, -fa[c]);
    }
}
