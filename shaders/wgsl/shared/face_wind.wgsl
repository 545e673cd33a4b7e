// What forces_springs_wind's particles start from (shared/spring_block.wgsl): the wind of
// the faces around each particle, computed from the positions — the faces as tri_normals
// computes them, summed in vertex_normals' slot order (core::grid's face slots), so the
// force is the one the two normal kernels would have left in the buffer.

@group(0) @binding(9) var<storage, read> triangles: array<u32>;
@group(0) @binding(10) var<storage, read> face_slots: array<i32>;

// Face normal and |N| of triangle (a, b, c), as tri_normals computes it.
fn face_of(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> vec4<f32> {
    let nrm = cross(b - a, c - a);
    return vec4<f32>(nrm, len3(nrm));
}

// The wind of a quad's two triangles, t0 = (x00, x01, x11) and t1 = (x00, x11, x10)
// (core::grid::build), zero for a quad off the grid.
struct QuadWind {
    t0: vec3<f32>,
    t1: vec3<f32>,
}

fn quad_wind(x00: vec3<f32>, x10: vec3<f32>, x01: vec3<f32>, x11: vec3<f32>, qi: i32, qj: i32) -> QuadWind {
    let m = i32(p.n) - 1;
    if qi < 0 || qj < 0 || qi >= m || qj >= m {
        return QuadWind(vec3<f32>(0.0), vec3<f32>(0.0));
    }
    return QuadWind(face_wind(face_of(x00, x01, x11)), face_wind(face_of(x00, x11, x10)));
}

// The wind on a particle from its six faces in slot order: up-left quad t0, t1, up-right
// t0, down-left t1, down-right t0, t1 (a face off the grid adds an exact zero where the
// slot walk would skip it).
fn vertex_wind(ul: QuadWind, ur: QuadWind, dl: QuadWind, dr: QuadWind) -> vec3<f32> {
    var w = vec3<f32>(0.0);
    w += ul.t0;
    w += ul.t1;
    w += ur.t0;
    w += dl.t1;
    w += dr.t0;
    w += dr.t1;
    return w;
}

// Block (row, c0): u, r, d are the positions of columns c0 - 1 … c0 + 4 in rows row - 1,
// row, row + 1. Its particles touch the quads of columns c0 - 1 … c0 + 3 in rows row - 1
// and row: each of those 20 faces computed once.
fn block_base(row: u32, c0: u32, u: array<vec3<f32>, 6>, r: array<vec3<f32>, 6>, d: array<vec3<f32>, 6>) -> Base4 {
    if !windy() {
        return Base4(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    }
    let c = i32(c0) - 1;
    let j = i32(row);
    let a0 = quad_wind(u[0], u[1], r[0], r[1], c, j - 1);
    let a1 = quad_wind(u[1], u[2], r[1], r[2], c + 1, j - 1);
    let a2 = quad_wind(u[2], u[3], r[2], r[3], c + 2, j - 1);
    let a3 = quad_wind(u[3], u[4], r[3], r[4], c + 3, j - 1);
    let a4 = quad_wind(u[4], u[5], r[4], r[5], c + 4, j - 1);
    let b0 = quad_wind(r[0], r[1], d[0], d[1], c, j);
    let b1 = quad_wind(r[1], r[2], d[1], d[2], c + 1, j);
    let b2 = quad_wind(r[2], r[3], d[2], d[3], c + 2, j);
    let b3 = quad_wind(r[3], r[4], d[3], d[4], c + 3, j);
    let b4 = quad_wind(r[4], r[5], d[4], d[5], c + 4, j);
    return Base4(
        vertex_wind(a0, a1, b0, b1),
        vertex_wind(a1, a2, b1, b2),
        vertex_wind(a2, a3, b2, b3),
        vertex_wind(a3, a4, b3, b4),
    );
}

// Face t computed from its corners in the triangle list (for wind_at, shared/wind_fn.wgsl).
fn face_at(t: u32) -> vec4<f32> {
    let k = 3u * t;
    return face_of(
        pos[world_base + triangles[k]].xyz,
        pos[world_base + triangles[k + 1u]].xyz,
        pos[world_base + triangles[k + 2u]].xyz,
    );
}

// Particle i (on the grid, any table): its faces from the slots, their corners from the
// triangle list.
fn particle_base(i: u32) -> vec3<f32> {
    return wind_at(i);
}
