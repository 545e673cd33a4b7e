// The strain limit's blocked window (strain_limit_pass.wgsl's pass, strain_count.wgsl's count)
// over shared/strain_points.wgsl's points: a block's window of 18 grid points (rows j - 1 …
// j + 1) and the entry point, one block an invocation.

// Grid point (c, r), which the lane on the left (right) holds as `theirs`: passed by a
// subgroup shuffle where the flavor has them and that lane holds the block beside,
// loaded otherwise (see shared/window_sh.wgsl).
fn left_point(theirs: Gp, c: i32, r: i32) -> Gp {
    let x4 = from_left4(theirs.x4);
    let n = i32(p.n);
    if have_left() {
        let inside = c >= 0 && c < n && r >= 0 && r < n;
        return Gp(u32(select(0, r * n + c, inside)), x4, inside);
    }
    return grid_point(c, r);
}

fn right_point(theirs: Gp, c: i32, r: i32) -> Gp {
    let x4 = from_right4(theirs.x4);
    let n = i32(p.n);
    if have_right() {
        let inside = c >= 0 && c < n && r >= 0 && r < n;
        return Gp(u32(select(0, r * n + c, inside)), x4, inside);
    }
    return grid_point(c, r);
}

// Block b at (row, c0) on the regular grid: the window of rows j - 1 … j + 1 loaded once
// — or, with shuffles, its own 12 points loaded and the 6 beside passed.
fn grid_block(b: u32, row: u32, c0: u32) {
    window_start(b, (p.n + BLOCK - 1u) / BLOCK);
    let r = i32(row);
    let c = i32(c0);
    // Rows j - 1, j, j + 1: columns c - 1 … c + 4, the block's own first.
    let u1 = grid_point(c, r - 1);
    let u2 = grid_point(c + 1, r - 1);
    let u3 = grid_point(c + 2, r - 1);
    let u4 = grid_point(c + 3, r - 1);
    let m1 = grid_point(c, r);
    let m2 = grid_point(c + 1, r);
    let m3 = grid_point(c + 2, r);
    let m4 = grid_point(c + 3, r);
    let d1 = grid_point(c, r + 1);
    let d2 = grid_point(c + 1, r + 1);
    let d3 = grid_point(c + 2, r + 1);
    let d4 = grid_point(c + 3, r + 1);
    let u0 = left_point(u4, c - 1, r - 1);
    let u5 = right_point(u1, c + 4, r - 1);
    let m0 = left_point(m4, c - 1, r);
    let m5 = right_point(m1, c + 4, r);
    let d0 = left_point(d4, c - 1, r + 1);
    let d5 = right_point(d1, c + 4, r + 1);
    // Particle k (at m[k + 1]), slots (-1,0) (1,0) (0,-1) (0,1) (-1,-1) (1,-1) (-1,1) (1,1)
    // = m[k] m[k+2] u[k+1] d[k+1] u[k] u[k+2] d[k] d[k+2].
    block_particle(row, c0, m1, m0, m2, u1, d1, u0, u2, d0, d2);
    block_particle(row, c0 + 1u, m2, m1, m3, u2, d2, u1, u3, d1, d3);
    block_particle(row, c0 + 2u, m3, m2, m4, u3, d3, u2, u4, d2, d4);
    block_particle(row, c0 + 3u, m4, m3, m5, u4, d4, u3, u5, d3, d5);
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
    // A uniform branch: each table mode does only its own loads.
    if interior.enabled != 0u {
        grid_block(b, row, c0);
        return;
    }
    // The table: storage buffers or the image (an irregular table, or table=storage|image).
    for (var k = 0u; k < BLOCK; k++) {
        if row < rows && c0 + k < width {
            table_particle(row * width + c0 + k);
        }
    }
}
