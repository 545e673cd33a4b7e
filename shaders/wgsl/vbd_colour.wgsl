//! include: state, table, aux, adjacency, colliders, range, vbd
//! worlds
// vbd_colour — one colour of Vertex Block Descent's sweep (core::cpu::vbd::vbd_colour and
// block_step): particles first … first + count − 1 of the colouring's list (binding 31,
// clothlab_core::tables::Colours; no two of a colour share a spring, so each reads only
// displacements no other invocation writes). Each gathers the force and the 3 × 3 Hessian of
// implicit Euler's energy at its particle — inertia m/h² (y − x), every spring of its row
// with its Hessian made positive semi-definite, Rayleigh damping on the ends' relative
// displacement — and steps by the block's solve (cofactors; no step where the
// determinant is not positive and finite). v' in aux0 (y − x⁰ = h v'), x⁰ in aux1, D in
// aux2: the step is added to D. Positions are x⁰ + D: a spring's ends are
// (x⁰ᵢ − x⁰ⱼ) + (Dᵢ − Dⱼ) apart, a few ulps of its length (core::cpu::vbd::VBD_AUX says
// why), and pos is written once, by vbd_finish.

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let range = pass_range;
    let k = flat_id(id, groups);
    if k >= range.count {
        return;
    }
    let i = colours[range.first + k];
    if !block_begin(i) {
        return;
    }
    aux2[world_base + i] = vec4<f32>(block_end(), 0.0);
}
