//! include: state, table, aux, adjacency, colliders, range, vbd
//! worlds
// vbd_colour_tri — one colour of Vertex Block Descent's sweep with the contact between
// triangles inside the solves (core::cpu::vbd::vbd_colour with TriVbd): vbd_colour's block,
// to which each particle adds the contact terms tri_vbd gathered for its colour (after the
// springs, before the colliders' contacts) and clears them; and the particle's position kept
// at the iterate x⁰ + D, where the next colour's terms are found. (Not the contact's
// include: GL allows llvmpipe's compute shaders 16 storage blocks.)

// The contact's integers (shared/tri.wgsl's): VBD's terms right after the scalars.
@group(0) @binding(40) var<storage, read_write> tri_ints: array<atomic<u32>>;

// Word k of the terms as f32, cleared (a batch's world's: from its integers' start,
// world_index times the words a world, which the contact's block carries).
fn take_term(k: u32) -> f32 {
    let at = world_index * contact_params.tri_world_words + k;
    let v = f32(bitcast<i32>(atomicLoad(&tri_ints[at])));
    atomicStore(&tri_ints[at], 0u);
    return v;
}

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let range = pass_range;
    let k = flat_id(id, groups);
    if k >= range.count {
        return;
    }
    let i = colours[range.first + k];
    // The colour's terms, taken and cleared (words written out: llvmpipe keeps a private
    // array indexed in a loop in memory, lane by lane).
    let w = TRI_AT_WORDS + VBD_TERMS * i;
    let f0 = take_term(w);
    let f1 = take_term(w + 1u);
    let f2 = take_term(w + 2u);
    let h0 = take_term(w + 3u);
    let h1 = take_term(w + 4u);
    let h2 = take_term(w + 5u);
    let h3 = take_term(w + 6u);
    let h4 = take_term(w + 7u);
    let h5 = take_term(w + 8u);
    if !block_begin(i) {
        return;
    }
    // core::cpu::vbd::tri_terms: the sums times the contact's stiffness.
    let kk = p.particle_mass / (p.dt * p.dt) * CONTACT_STIFFNESS;
    let fu = kk * (p.self_thickness * (1.0 / CONTACT_UNITS));
    let hu = kk * (1.0 / CONTACT_UNITS);
    force_acc += vec3<f32>(f0, f1, f2) * fu;
    hess[0] += h0 * hu;
    hess[1] += h1 * hu;
    hess[2] += h2 * hu;
    hess[3] += h3 * hu;
    hess[4] += h4 * hu;
    hess[5] += h5 * hu;
    let d = block_end();
    aux2[world_base + i] = vec4<f32>(d, 0.0);
    let x4 = aux1[world_base + i];
    pos[world_base + i] = vec4<f32>(x4.xyz + d, x4.w);
}
