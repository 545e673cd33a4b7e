// The adjoint of a substep's planes (clothlab_core::layout::Buf::Adjoint): ADJ_ROWS planes
// of a vec4 a particle, plane r of particle i at r · N + i (clothlab_cpu::adjoint).
@group(0) @binding(42) var<storage, read_write> adjoint: array<vec4<f32>>;

// Plane r of particle i.
fn adj_at(r: u32, i: u32) -> u32 {
    return r * num_particles() + i;
}

// A contact's velocity taken back (clothlab_cpu::adjoint::slide_back): v' = (v − vn n) keep
// + max(vn, 0) n onto gv; the gradient with respect to v, to n (in g_n) and to the friction
// (in g_f).
struct Slid {
    g_v: vec3<f32>,
    g_n: vec3<f32>,
    g_f: f32,
}

fn slide_back(v: vec3<f32>, n: vec3<f32>, gv: vec3<f32>) -> Slid {
    let vn = dot3(v, n);
    let keep = 1.0 - p.friction;
    let on = select(0.0, 1.0, vn > 0.0);
    let gvn = dot3(n, gv);
    let g_v = (gv - gvn * n) * keep + (on * gvn) * n;
    let g_n = (on - keep) * (vn * gv + gvn * v);
    return Slid(g_v, g_n, -dot3(v - vn * n, gv));
}
