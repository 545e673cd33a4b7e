//! include: state, aux, xpbd, range
//! worlds
// xpbd_mesh — one XPBD pass of a mesh (core::cpu::integrators::xpbd_mesh_pass): springs
// first … first + count − 1 of the spring list, one colour of its greedy colouring (the
// list is sorted by pass when the mesh is built: clothlab_core::grid::MeshTables), so no
// two share a particle. The range comes in immediates, one dispatch per pass. Spring k's
// λ is word k of aux0 then aux1 (a mesh has at most 6 springs per particle: every vertex
// holds at most SLOTS = 12 spring ends, so 8 words per particle are room enough).

// The spring list in two halves, as springs_scatter reads it.
@group(0) @binding(7) var<storage, read> springs: array<Spring>;
@group(0) @binding(15) var<storage, read> springs_b: array<Spring>;

fn spring_at(k: u32) -> Spring {
    let half = arrayLength(&springs);
    if k < half {
        return springs[k];
    }
    return springs_b[k - half];
}

fn mesh_lambda(k: u32) -> f32 {
    let words = 4u * p.num_particles;
    if k < words {
        return aux0[world_base + k / 4u][k % 4u];
    }
    return aux1[world_base + (k - words) / 4u][(k - words) % 4u];
}

fn set_mesh_lambda(k: u32, l: f32) {
    let words = 4u * p.num_particles;
    if k < words {
        aux0[world_base + k / 4u][k % 4u] = l;
    } else {
        aux1[world_base + (k - words) / 4u][(k - words) % 4u] = l;
    }
}

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let range = pass_range;
    let i = flat_id(id, groups);
    if i >= range.count {
        return;
    }
    let k = range.first + i;
    let s = spring_at(k);
    if s.ks <= 0.0 {
        return;
    }
    let l = mesh_lambda(k);
    let r = xpbd_solve(s.a, s.b, SpringSlot(i32(s.b), s.rest, s.ks, s.kd), l);
    if r.moved {
        set_mesh_lambda(k, l + r.dl);
    }
}
