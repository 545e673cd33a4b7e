// forces + springs fused (optimized variant): at most one read and one write of the force, four
// consecutive particles of a row (BLOCK) per invocation. Their 4 × 13 points overlap:
// loading the 28 distinct ones once (a window of rows j - 2 … j + 2) reads 46 % fewer
// positions than a particle per invocation. On a regular grid (interior.enabled) there are
// no table reads and no branches around loads; otherwise (an irregular table, or
// `table=storage|image`) each particle walks its table and the window is not loaded: the
// branch is uniform, so every mode does only its own loads.
//
// What a particle's force starts from before gravity, drag and its springs comes from the
// including kernel: `block_base` (four particles of the regular grid, given the window's
// positions) and `particle_base` (one particle, from the table). forces_springs reads the
// force buffer, where the normals kernel of the substep before left the wind
// (shared/force_buffer.wgsl); forces_springs_wind computes the wind of the faces around
// each particle here, from the positions (shared/face_wind.wgsl, `normals=frame`).

// What the four particles of a block start from (the including kernel's `block_base`).
struct Base4 {
    k0: vec3<f32>,
    k1: vec3<f32>,
    k2: vec3<f32>,
    k3: vec3<f32>,
}

// Force on particle k of the block: a its point, base what its force starts from, s0 … s11
// its neighbours in slot order.
fn block_particle(
    row: u32, col: u32, a: Nb, base: vec3<f32>, s0: Nb, s1: Nb, s2: Nb, s3: Nb, s4: Nb, s5: Nb,
    s6: Nb, s7: Nb, s8: Nb, s9: Nb, s10: Nb, s11: Nb,
) {
    let i = row * p.n + col;
    let f = forces_at_mean(vec4<f32>(base, 0.0), a.pt.v).xyz;
    let acc = grid_springs(f, a.pt, s0, s1, s2, s3, s4, s5, s6, s7, s8, s9, s10, s11);
    if a.inside && interior.enabled != 0u {
        force[world_base + i] = vec4<f32>(acc, 0.0);
    }
}

// Grid point (c, r), which the lane on the left (right) holds as its point `theirs`: passed
// by a subgroup shuffle where the flavor has them and that lane holds the block beside
// (shared/window_sh.wgsl), loaded otherwise.
fn left_point(theirs: Nb, c: i32, r: i32) -> Nb {
    let x = from_left3(theirs.pt.x);
    let v = from_left3(theirs.pt.v);
    if have_left() {
        return Nb(Pt(x, v), on_grid(c, r));
    }
    return grid_point(c, r);
}

fn right_point(theirs: Nb, c: i32, r: i32) -> Nb {
    let x = from_right3(theirs.pt.x);
    let v = from_right3(theirs.pt.v);
    if have_right() {
        return Nb(Pt(x, v), on_grid(c, r));
    }
    return grid_point(c, r);
}

// Block b at (row, c0) on the regular grid: the window of rows j - 2 … j + 2, each of its
// 28 points loaded once — or, with shuffles, its own 20 loaded and the 8 beside passed.
fn grid_block(b: u32, row: u32, c0: u32) {
    window_start(b, (p.n + BLOCK - 1u) / BLOCK);
    let r = i32(row);
    let c = i32(c0);
    // Row j: columns c - 2 … c + 5; rows j ± 1: c - 1 … c + 4; rows j ± 2: c … c + 3. A
    // block's own columns first, then those of the blocks beside (their c + 2 … c + 3 on
    // the left, c … c + 1 on the right).
    let r2 = grid_point(c, r);
    let r3 = grid_point(c + 1, r);
    let r4 = grid_point(c + 2, r);
    let r5 = grid_point(c + 3, r);
    let u1 = grid_point(c, r - 1);
    let u2 = grid_point(c + 1, r - 1);
    let u3 = grid_point(c + 2, r - 1);
    let u4 = grid_point(c + 3, r - 1);
    let d1 = grid_point(c, r + 1);
    let d2 = grid_point(c + 1, r + 1);
    let d3 = grid_point(c + 2, r + 1);
    let d4 = grid_point(c + 3, r + 1);
    let uu0 = grid_point(c, r - 2);
    let uu1 = grid_point(c + 1, r - 2);
    let uu2 = grid_point(c + 2, r - 2);
    let uu3 = grid_point(c + 3, r - 2);
    let dd0 = grid_point(c, r + 2);
    let dd1 = grid_point(c + 1, r + 2);
    let dd2 = grid_point(c + 2, r + 2);
    let dd3 = grid_point(c + 3, r + 2);
    let r0 = left_point(r4, c - 2, r);
    let r1 = left_point(r5, c - 1, r);
    let r6 = right_point(r2, c + 4, r);
    let r7 = right_point(r3, c + 5, r);
    let u0 = left_point(u4, c - 1, r - 1);
    let u5 = right_point(u1, c + 4, r - 1);
    let d0 = left_point(d4, c - 1, r + 1);
    let d5 = right_point(d1, c + 4, r + 1);
    // Columns c0 - 1 … c0 + 4 of rows j - 1, j, j + 1.
    let base = block_base(
        row,
        c0,
        array<vec3<f32>, 6>(u0.pt.x, u1.pt.x, u2.pt.x, u3.pt.x, u4.pt.x, u5.pt.x),
        array<vec3<f32>, 6>(r1.pt.x, r2.pt.x, r3.pt.x, r4.pt.x, r5.pt.x, r6.pt.x),
        array<vec3<f32>, 6>(d0.pt.x, d1.pt.x, d2.pt.x, d3.pt.x, d4.pt.x, d5.pt.x),
    );
    // Particle k (at r[k + 2]), slots (-1,0) (1,0) (0,-1) (0,1) (-1,-1) (1,-1) (-1,1) (1,1)
    // (-2,0) (2,0) (0,-2) (0,2) = r[k+1] r[k+3] u[k+1] d[k+1] u[k] u[k+2] d[k] d[k+2] r[k]
    // r[k+4] uu[k] dd[k].
    block_particle(row, c0, r2, base.k0, r1, r3, u1, d1, u0, u2, d0, d2, r0, r4, uu0, dd0);
    block_particle(row, c0 + 1u, r3, base.k1, r2, r4, u2, d2, u1, u3, d1, d3, r1, r5, uu1, dd1);
    block_particle(row, c0 + 2u, r4, base.k2, r3, r5, u3, d3, u2, u4, d2, d4, r2, r6, uu2, dd2);
    block_particle(row, c0 + 3u, r5, base.k3, r4, r6, u4, d4, u3, u5, d3, d5, r3, r7, uu3, dd3);
}

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    interior = interior_slots;
    let b = flat_id(id, groups);
    let rows = block_rows_of(p);
    let width = block_width_of(p);
    let origin = block_origin(b, width);
    let row = origin.x;
    let c0 = origin.y;
    if interior.enabled != 0u {
        grid_block(b, row, c0);
        return;
    }
    // The table: storage buffers or the image (an irregular table, or table=storage|image),
    // each particle's own mass (a mesh's vary; ×1 on a grid).
    for (var k = 0u; k < BLOCK; k++) {
        let i = row * width + c0 + k;
        if row < rows && c0 + k < width {
            let a = point(i);
            let f = forces_at(vec4<f32>(particle_base(i), 0.0), a.v, pos[world_base + i].w);
            force[world_base + i] = vec4<f32>(table_springs(i, a, f.xyz), 0.0);
        }
    }
}
