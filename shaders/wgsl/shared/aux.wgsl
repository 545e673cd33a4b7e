// The integrators' scratch buffers (core::cpu::integrators: RK2/RK4 keep x₀, v₀, the stage
// sums and the wind; implicit keeps Δv, r (w: the preconditioner's diagonal), p, q and
// the per-workgroup partial sums in aux4) and the conjugate-gradient scalars.
@group(0) @binding(24) var<storage, read_write> aux0: array<vec4<f32>>;
@group(0) @binding(25) var<storage, read_write> aux1: array<vec4<f32>>;
@group(0) @binding(26) var<storage, read_write> aux2: array<vec4<f32>>;
@group(0) @binding(27) var<storage, read_write> aux3: array<vec4<f32>>;
@group(0) @binding(28) var<storage, read_write> aux4: array<vec4<f32>>;
// r·z, p·q, α, β.
@group(0) @binding(29) var<storage, read_write> scalars: array<vec4<f32>>;

// The sum of v over the workgroup, in a tree through workgroup memory (no subgroups, so
// that it runs on every adapter). Every invocation must call it (a barrier inside).
var<workgroup> wg_sum_acc: array<f32, WORKGROUP>;

fn workgroup_sum(v: f32, li: u32) -> f32 {
    wg_sum_acc[li] = v;
    workgroupBarrier();
    for (var s = WORKGROUP / 2u; s > 0u; s >>= 1u) {
        if li < s {
            wg_sum_acc[li] += wg_sum_acc[li + s];
        }
        workgroupBarrier();
    }
    return wg_sum_acc[0];
}

// Stores a workgroup's partial sum where the reduction kernels fold them (aux4[g].x; a
// batch's world's in its own rows).
fn store_partial(total: f32, li: u32, wg: vec3<u32>, groups: vec3<u32>) {
    let g = wg.x + wg.y * groups.x;
    if li == 0u && world_base + g < arrayLength(&aux4) {
        aux4[world_base + g] = vec4<f32>(total, 0.0, 0.0, 0.0);
    }
}

// The fold of every workgroup's partial sum (one workgroup runs it): strided sums per
// invocation, then the tree.
fn fold_partials(li: u32) -> f32 {
    let count = (p.num_particles + WORKGROUP - 1u) / WORKGROUP;
    var acc = 0.0;
    for (var k = li; k < count; k += WORKGROUP) {
        acc += aux4[world_base + k].x;
    }
    return workgroup_sum(acc, li);
}

// core::cpu::integrators::precondition: z = r / diag (zero for held particles).
fn precondition(r4: vec4<f32>) -> vec3<f32> {
    return select(vec3<f32>(0.0), r4.xyz / r4.w, r4.w > 0.0);
}
