//! include: state, table, aux, adjacency
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

@group(0) @binding(31) var<storage, read> colours: array<u32>;

struct PassRange {
    first: u32,
    count: u32,
}
var<immediate> pass_range: PassRange;

// H⁻¹ f for the symmetric H = [a b c; b d g; c g e] (core::cpu::vbd::solve_sym3).
fn solve_sym3(a: f32, d: f32, e: f32, b: f32, c: f32, g: f32, f: vec3<f32>) -> vec3<f32> {
    let c00 = d * e - g * g;
    let c01 = c * g - b * e;
    let c02 = b * g - c * d;
    let det = a * c00 + b * c01 + c * c02;
    if !(det > 0.0 && det <= 3.40282347e38) {
        return vec3<f32>(0.0);
    }
    let c11 = a * e - c * c;
    let c12 = b * c - a * g;
    let c22 = a * d - b * b;
    let r = 1.0 / det;
    return vec3<f32>(
        (c00 * f.x + c01 * f.y + c02 * f.z) * r,
        (c01 * f.x + c11 * f.y + c12 * f.z) * r,
        (c02 * f.x + c12 * f.y + c22 * f.z) * r,
    );
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
    let x4 = aux1[i];
    if held(i, x4.w) {
        return;
    }
    let h = p.dt;
    let x0 = x4.xyz;
    let inertia = mass_of(x4.w) / (h * h);
    let moved = aux2[i].xyz;
    var f = (aux0[i].xyz * h - moved) * inertia;
    var d0 = inertia;
    var d1 = inertia;
    var d2 = inertia;
    var o01 = 0.0;
    var o02 = 0.0;
    var o12 = 0.0;
    let r = slot_row(i);
    for (var s = 0u; s < r.count; s++) {
        let slot = row_slot(i, r, s);
        let other = slot_other(slot);
        if other < 0 || slot.ks <= 0.0 {
            continue;
        }
        let j = u32(other);
        let u = moved - aux2[j].xyz;
        let dx = (x0 - aux1[j].xyz) + u;
        let l = len3(dx);
        if l <= 1.17549435e-38 {
            continue;
        }
        let n = dx * (1.0 / l);
        let a = slot.ks * max(1.0 - slot.rest / l, 0.0);
        let b = slot.ks - a;
        f -= n * (slot.ks * (l - slot.rest));
        var scale = 1.0;
        if slot.kd > 0.0 {
            let c = slot.kd / (slot.ks * h);
            let hu = u * a + n * (b * dot3(n, u));
            f -= hu * c;
            scale = 1.0 + c;
        }
        let sa = a * scale;
        let sb = b * scale;
        d0 += sa + sb * n.x * n.x;
        d1 += sa + sb * n.y * n.y;
        d2 += sa + sb * n.z * n.z;
        o01 += sb * n.x * n.y;
        o02 += sb * n.x * n.z;
        o12 += sb * n.y * n.z;
    }
    let step = solve_sym3(d0, d1, d2, o01, o02, o12, f);
    aux2[i] = vec4<f32>(moved + step, 0.0);
}
