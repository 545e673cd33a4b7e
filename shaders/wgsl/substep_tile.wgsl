//! include: state, table, gather, wind_fn, face_wind, adjacency, colliders, strain_fn
//! no table image
// substep_tile — the whole Verlet substep of a regular grid in one dispatch
// (`fusion=tile`): forces + springs with the wind of the faces around each particle,
// integrate + collide, then `strain_passes` passes of the strain limit with the tethers,
// all on a square region of the grid held in workgroup memory. Each workgroup loads its
// tile and a halo as deep as the stages reach (2 for the springs' bend neighbours, 2 more
// per strain pass: a pass divides by its neighbours' counts, which their neighbours
// decide), runs the stages with barriers between them, every stage on a region one reach
// smaller than the stage before (its invocations on that square's points only), and writes
// only its tile — the dispatch's last stage straight from its results: new positions into
// the other buffer of the pair, new velocities into aux0 (`tile_vel` puts them into place
// after the swap — other workgroups still read this substep's velocities in their halos).
// `tile_substeps` substeps per dispatch (temporal blocking) with a halo that many times as
// deep. Every stage is the arithmetic of its unfused kernel (forces_springs_wind,
// integrate_collide, strain_count, strain_limit) on the same points in the same order,
// so the result is theirs bit for bit (core's twins: engine::kernels::substep_tile).

@group(0) @binding(5) var<storage, read_write> pos_out: array<vec4<f32>>;
@group(0) @binding(24) var<storage, read_write> vel_out: array<vec4<f32>>;

// What face_wind.wgsl's block_base returns (spring_block.wgsl's, which this kernel does not
// include: it has its own entry point).
struct Base4 {
    k0: vec3<f32>,
    k1: vec3<f32>,
    k2: vec3<f32>,
    k3: vec3<f32>,
}

// The region's side (tile + halo on both sides), its points, the invocations and how many
// region points each takes in a stage. 32 × 32 points of 32 bytes (two `vec4`): 32 KiB of
// workgroup memory (engine::kernels::TILE_WORKGROUP_BYTES; the solver refuses the rung where the
// adapter has less).
const REGION: i32 = 32;
const REGION_POINTS: u32 = 1024u;
const TILE_THREADS: u32 = 256u;
const PER_THREAD: u32 = 4u;

// Positions (w: the inverse-mass flag) and velocities (w: the strain pass's count of
// over-stretched springs, which the velocity does not need): one `vec4` load each per
// point, the form in which drivers that emulate these loads lane by lane (llvmpipe) pay
// least.
var<workgroup> tx: array<vec4<f32>, REGION_POINTS>;
var<workgroup> tv: array<vec4<f32>, REGION_POINTS>;

// The grid column and row of region point (0, 0).
var<private> origin: vec2<i32>;
// Each invocation's results of a stage, written back after the stage's barrier.
var<private> rx: array<vec4<f32>, PER_THREAD>;
var<private> rv: array<vec3<f32>, PER_THREAD>;

// A tile's side with halo h on each side.
fn tile_side(h: i32) -> i32 {
    return REGION - 2 * h;
}

// The halo one substep needs: 2 for the springs, 2 per strain pass.
fn substep_reach(passes: u32) -> i32 {
    return 2 + 2 * i32(passes);
}

// Region point k of the invocation's m-th: its region column and row.
fn region_cr(k: u32) -> vec2<i32> {
    return vec2<i32>(i32(k % u32(REGION)), i32(k / u32(REGION)));
}

fn region_index(c: i32, r: i32) -> u32 {
    return u32(r * REGION + c);
}

// Whether region point (c, r) lies on the grid, and its particle.
fn region_inside(c: i32, r: i32) -> bool {
    return on_grid(origin.x + c, origin.y + r);
}

fn region_particle(c: i32, r: i32) -> u32 {
    return u32((origin.y + r) * i32(p.n) + origin.x + c);
}

// A stage's k-th point: the stage's points are the square `m` inside the region's border
// (less what lies off the grid: `region_inside`), taken densely so that the invocations
// of a stage work on its points only — not on the whole region with most lanes idle, which
// drivers that run a SIMD group's masked lanes (llvmpipe) pay for (−10 to −18 % there at
// n ≥ 128: docs/variants.md).
fn stage_points(m: i32) -> u32 {
    let side = u32(REGION - 2 * m);
    return side * side;
}

fn stage_cr(k: u32, m: i32) -> vec2<i32> {
    let side = u32(REGION - 2 * m);
    return vec2<i32>(m + i32(k % side), m + i32(k / side));
}

fn region_x(c: i32, r: i32) -> vec3<f32> {
    return tx[region_index(c, r)].xyz;
}

fn region_v(k: u32) -> vec3<f32> {
    return tv[k].xyz;
}

// Region point (c, r) as the gather's neighbour.
fn region_nb(c: i32, r: i32) -> Nb {
    let k = region_index(c, r);
    return Nb(Pt(tx[k].xyz, region_v(k)), region_inside(c, r));
}

// A pin's current position (for the tethers): pins do not move in a substep, the grab's
// particle is at its target (state.wgsl's integrated_with).
fn pin_point(pin: u32) -> vec3<f32> {
    if i32(pin) == p.grab_index {
        return p.grab_target.xyz;
    }
    return pos[pin].xyz;
}

// forces_springs_wind and integrate_collide for region point (c, r): its new point.
fn force_and_move(c: i32, r: i32) -> Moved {
    let a = region_nb(c, r);
    let col = origin.x + c;
    let row = origin.y + r;
    // Its 12 spring neighbours in slot order, each loaded once: (-1,0) (1,0) (0,-1) (0,1)
    // (-1,-1) (1,-1) (-1,1) (1,1) (-2,0) (2,0) (0,-2) (0,2).
    let s0 = region_nb(c - 1, r);
    let s1 = region_nb(c + 1, r);
    let s2 = region_nb(c, r - 1);
    let s3 = region_nb(c, r + 1);
    let s4 = region_nb(c - 1, r - 1);
    let s5 = region_nb(c + 1, r - 1);
    let s6 = region_nb(c - 1, r + 1);
    let s7 = region_nb(c + 1, r + 1);
    // The wind of its six faces from the same points (face_wind.wgsl's block_base for one
    // particle: quads up-left, up-right, down-left, down-right; a corner off the grid holds
    // zeros, and its quad's wind is zero).
    var base = vec3<f32>(0.0);
    if windy() {
        let ul = quad_wind(s4.pt.x, s2.pt.x, s0.pt.x, a.pt.x, col - 1, row - 1);
        let ur = quad_wind(s2.pt.x, s5.pt.x, a.pt.x, s1.pt.x, col, row - 1);
        let dl = quad_wind(s0.pt.x, a.pt.x, s6.pt.x, s3.pt.x, col - 1, row);
        let dr = quad_wind(a.pt.x, s1.pt.x, s3.pt.x, s7.pt.x, col, row);
        base = vertex_wind(ul, ur, dl, dr);
    }
    let f = forces_at_mean(vec4<f32>(base, 0.0), a.pt.v).xyz;
    let acc = grid_springs(
        f,
        a.pt,
        s0,
        s1,
        s2,
        s3,
        s4,
        s5,
        s6,
        s7,
        region_nb(c - 2, r),
        region_nb(c + 2, r),
        region_nb(c, r - 2),
        region_nb(c, r + 2),
    );
    let i = region_particle(c, r);
    let x4 = tx[region_index(c, r)];
    var m = integrated_with(i, x4, a.pt.v, acc);
    if is_free(i, x4.w) {
        m = collided(m);
    }
    return m;
}

// The strain-limited neighbour offsets in slot order (core::grid::SLOT_OFFSETS).
const STRAIN_DC = array<i32, 8>(-1, 1, 0, 0, -1, 1, -1, 1);
const STRAIN_DR = array<i32, 8>(0, 0, -1, 1, -1, -1, 1, 1);

// strain_count for region point (c, r).
fn count_at(c: i32, r: i32) -> f32 {
    let xi = region_x(c, r);
    var n = 0.0;
    for (var s = 0u; s < STRAIN_SLOTS; s++) {
        let bc = c + STRAIN_DC[s];
        let br = r + STRAIN_DR[s];
        n += select(0.0, over(xi, tx[region_index(bc, br)], interior.slots[s].rest), region_inside(bc, br));
    }
    return n;
}

// strain_limit for region point (c, r): its corrected point and the velocity its move
// implies (strain_limit_pass.wgsl's block_particle and store_point).
fn limit_at(c: i32, r: i32) -> Moved {
    let k = region_index(c, r);
    let x4 = tx[k];
    let i = region_particle(c, r);
    let xi = x4.xyz;
    let wi = mobility(i, x4.w);
    let ci = tv[k].w;
    var corr = Correction(vec3<f32>(0.0), 0.0);
    for (var s = 0u; s < STRAIN_SLOTS; s++) {
        let bc = c + STRAIN_DC[s];
        let br = r + STRAIN_DR[s];
        if region_inside(bc, br) {
            let kb = region_index(bc, br);
            limit_spring(&corr, region_particle(bc, br), tx[kb], interior.slots[s].rest, xi, wi, ci, tv[kb].w);
        }
    }
    let out = finish(i, x4, wi, corr);
    return Moved(out.xyz, region_v(k) + (out.xyz - x4.xyz) * (1.0 / p.dt));
}

// Writes back this invocation's results of a stage over the points `m` inside the border.
fn store_stage(tid: u32, m: i32) {
    var j = 0u;
    for (var k = tid; k < stage_points(m); k += TILE_THREADS) {
        let cr = stage_cr(k, m);
        if region_inside(cr.x, cr.y) {
            let kr = region_index(cr.x, cr.y);
            tx[kr] = rx[j];
            tv[kr] = vec4<f32>(rv[j], 0.0);
        }
        j++;
    }
}

// Writes this invocation's results of the dispatch's last stage, whose points `m` inside
// the border are the tile's (m = the halo: the last strain pass's, or the forces' without
// one), as the tile's new state: positions into the other buffer of the pair, velocities
// into aux0.
fn write_tile(tid: u32, m: i32) {
    var j = 0u;
    for (var k = tid; k < stage_points(m); k += TILE_THREADS) {
        let cr = stage_cr(k, m);
        if region_inside(cr.x, cr.y) {
            let i = region_particle(cr.x, cr.y);
            pos_out[i] = rx[j];
            vel_out[i] = vec4<f32>(rv[j], 0.0);
        }
        j++;
    }
}

@compute @workgroup_size(256)
fn main(@builtin(local_invocation_index) tid: u32, @builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    interior = interior_slots;
    // The loop bounds straight from the constants' binding (uniform values: the barriers
    // inside the loops are reached by every invocation); the private copy `p` is not
    // known to be uniform.
    let passes = step_params.strain_passes;
    let substeps = max(step_params.tile_substeps, 1u);
    let n = i32(p.n);
    // A cloth that fits one region has no neighbours outside it: no halo, every stage on
    // every point, as many substeps as asked (a whole frame in one dispatch). `unit`
    // scales every margin: 1 with tiles, 0 then.
    let unit = select(1, 0, n <= REGION);
    let reach = substep_reach(passes) * unit;
    let halo = reach * i32(substeps);
    let side = tile_side(halo);
    let per_row = (n + side - 1) / side;
    let t = i32(wg.x + wg.y * groups.x);
    origin = vec2<i32>((t % per_row) * side - halo, (t / per_row) * side - halo);
    // Load the region (zeros off the grid: never used, every use checks `inside`).
    for (var k = tid; k < REGION_POINTS; k += TILE_THREADS) {
        let cr = region_cr(k);
        var x4 = vec4<f32>(0.0);
        var v = vec4<f32>(0.0);
        if region_inside(cr.x, cr.y) {
            let i = region_particle(cr.x, cr.y);
            x4 = pos[i];
            v = vel[i];
        }
        tx[k] = x4;
        tv[k] = vec4<f32>(v.xyz, 0.0);
    }
    workgroupBarrier();
    for (var sub = 0u; sub < substeps; sub++) {
        // Forces, springs, wind, integrate, collide: every point 2 inside what is valid.
        let m0 = i32(sub) * reach + 2 * unit;
        var j = 0u;
        for (var k = tid; k < stage_points(m0); k += TILE_THREADS) {
            let cr = stage_cr(k, m0);
            if region_inside(cr.x, cr.y) {
                let moved = force_and_move(cr.x, cr.y);
                rx[j] = vec4<f32>(moved.x, tx[region_index(cr.x, cr.y)].w);
                rv[j] = moved.v;
            }
            j++;
        }
        // The dispatch's last stage computed exactly the tile's points: out they go (no
        // store into the region, no two barriers). Otherwise into the region.
        if sub + 1u == substeps && passes == 0u {
            write_tile(tid, m0);
        } else {
            workgroupBarrier();
            store_stage(tid, m0);
            workgroupBarrier();
        }
        for (var s = 0u; s < passes; s++) {
            // The counts one inside what is valid, the pass two inside.
            let mc = m0 + (2 * i32(s) + 1) * unit;
            let ml = mc + unit;
            for (var k = tid; k < stage_points(mc); k += TILE_THREADS) {
                let cr = stage_cr(k, mc);
                if region_inside(cr.x, cr.y) {
                    tv[region_index(cr.x, cr.y)].w = count_at(cr.x, cr.y);
                }
            }
            workgroupBarrier();
            j = 0u;
            for (var k = tid; k < stage_points(ml); k += TILE_THREADS) {
                let cr = stage_cr(k, ml);
                if region_inside(cr.x, cr.y) {
                    let moved = limit_at(cr.x, cr.y);
                    rx[j] = vec4<f32>(moved.x, tx[region_index(cr.x, cr.y)].w);
                    rv[j] = moved.v;
                }
                j++;
            }
            if sub + 1u == substeps && s + 1u == passes {
                write_tile(tid, ml);
            } else {
                workgroupBarrier();
                store_stage(tid, ml);
                workgroupBarrier();
            }
        }
    }
}
