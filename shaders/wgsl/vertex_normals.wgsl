//! include: wind, wind_fn, adjacency
//! worlds
// vertex_normals — per particle: sum of the adjacent face normals (gathered in slot order),
// normalised, and the wind force into the force buffer (optimized variant): each face is
// read once for both.

// The normal sum and the wind force of the faces gathered so far.
struct Gathered {
    sum: vec3<f32>,
    wind: vec3<f32>,
}

fn add_face(g: ptr<function, Gathered>, t: u32, wind: bool) {
    let f4 = faces[face_base + t];
    (*g).sum += f4.xyz;
    if wind {
        (*g).wind += face_wind(f4);
    }
}

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    let n = p.n;
    if i >= p.num_particles {
        return;
    }
    let wind = windy();
    var g = Gathered(vec3<f32>(0.0), vec3<f32>(0.0));
    // Away from the border all six faces exist, numbered as core::grid::build numbers them
    // (triangles 2q and 2q + 1 of quad q = qj (n - 1) + qi): no face-slot reads. The border
    // walks its slots in a loop interior particles do not enter, as does every vertex of a
    // mesh (n = 0).
    let col = i % max(n, 1u);
    let row = i / max(n, 1u);
    let inner = col >= 1u && col + 1u < n && row >= 1u && row + 1u < n;
    if inner {
        let up = 2u * ((row - 1u) * (n - 1u) + col - 1u);
        let down = 2u * (row * (n - 1u) + col - 1u);
        add_face(&g, up, wind);
        add_face(&g, up + 1u, wind);
        add_face(&g, up + 2u, wind);
        add_face(&g, down + 1u, wind);
        add_face(&g, down + 2u, wind);
        add_face(&g, down + 3u, wind);
    }
    let r = face_row(i);
    let slots = select(r.count, 0u, inner);
    for (var s = 0u; s < slots; s++) {
        let t = face_slots[r.first + s];
        if t >= 0 {
            add_face(&g, u32(t), wind);
        }
    }
    normal[world_base + i] = vec4<f32>(normalize_or_zero(g.sum), 0.0);
    force[world_base + i] = vec4<f32>(g.wind, 0.0);
}
