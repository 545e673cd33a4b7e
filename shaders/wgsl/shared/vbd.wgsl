// Vertex Block Descent's block (core::cpu::vbd::block_step), shared by vbd_colour and
// vbd_colour_tri: a particle's force and 3 × 3 Hessian of implicit Euler's energy — inertia,
// its row's springs, the colliders' penalties and friction — and the block's solve.

@group(0) @binding(31) var<storage, read> colours: array<u32>;

// core::cpu::vbd's contact constants.
const CONTACT_STIFFNESS: f32 = 1000.0;
const CONTACT_REACH: f32 = 0.1;
const FRICTION_EPS_V: f32 = 0.01;

// The block [h00, h11, h22, h01, h02, h12] and the force being gathered.
var<private> hess: array<f32, 6>;
var<private> force_acc: vec3<f32>;

// Adds a I + b n̂n̂ᵀ to the block (core::cpu::vbd::add_block).
fn add_block(a: f32, b: f32, n: vec3<f32>) {
    hess[0] += kept(a + kept(b * n.x * n.x));
    hess[1] += kept(a + kept(b * n.y * n.y));
    hess[2] += kept(a + kept(b * n.z * n.z));
    hess[3] += kept(b * n.x * n.y);
    hess[4] += kept(b * n.x * n.z);
    hess[5] += kept(b * n.y * n.z);
}

// `x` through a word that is 0 but that the compiler cannot know is (ContactParams's
// `zero`, a core::step_params::ZeroWord: 0 by its type), so that the block's sums stay the twin's: lavapipe's compiler otherwise
// evaluated the running sum of a + b·n.x·n.x differently (its terms summed apart were the
// twin's bits, the sum one ulp off), and VBD's rollouts left the CPU's bits.
fn kept(x: f32) -> f32 {
    return bitcast<f32>(bitcast<u32>(x) | contact_params.zero);
}

// The block and force after the penalties (the friction pass's λ reads them).
var<private> hess_n: array<f32, 6>;
var<private> force_n: vec3<f32>;

// A contact of penetration pen along n̂ for a vertex that moved d (core::cpu::vbd::contacts):
// the penalty's force and Hessian (first pass), or the smoothed Coulomb friction's with
// λ = k max(0, pen − n̂·f / n̂ᵀHn̂) from the block after the penalties (second pass).
fn touch(stiffness: f32, pen: f32, n: vec3<f32>, d: vec3<f32>, vs: vec3<f32>, friction_pass: bool) {
    if !friction_pass {
        force_acc += n * (stiffness * pen);
        add_block(0.0, stiffness, n);
        return;
    }
    let ha = hess_n;
    let hn = n.x * (ha[0] * n.x + ha[3] * n.y + ha[4] * n.z)
        + n.y * (ha[3] * n.x + ha[1] * n.y + ha[5] * n.z)
        + n.z * (ha[4] * n.x + ha[5] * n.y + ha[2] * n.z);
    let lambda = stiffness * max(pen - dot3(n, force_n) / hn, 0.0);
    let eps = FRICTION_EPS_V * p.dt;
    // The displacement relative to the surface (a moving collider's moved vs·h).
    let dr = d - vs * p.dt;
    let u = dr - n * dot3(n, dr);
    let y = sqrt(dot3(u, u));
    var c = 1.0 / y;
    if y < eps {
        c = 2.0 / eps - y / (eps * eps);
    }
    let w = vbd_mu() * lambda * c;
    force_acc -= u * w;
    add_block(w, -w, n);
}

// The floor, then every collider in scene order, each grown by the margin and its reach
// (core::cpu::vbd::each_contact).
fn each_contact(stiffness: f32, x: vec3<f32>, d: vec3<f32>, friction_pass: bool) {
    let reach = p.margin + p.margin * CONTACT_REACH;
    let f = floor_contact(p.floor_y, x, reach);
    if f.hit {
        touch(stiffness, f.depth, f.n, d, f.vs, friction_pass);
    }
    for (var k = 0u; k < p.num_spheres; k++) {
        let c = sphere_contact(spheres[k], x, reach);
        if c.hit {
            touch(stiffness, c.depth, c.n, d, c.vs, friction_pass);
        }
    }
    for (var k = 0u; k < p.num_boxes; k++) {
        let c = box_contact(boxes[k], x, reach);
        if c.hit {
            touch(stiffness, c.depth, c.n, d, c.vs, friction_pass);
        }
    }
    if USES_RODS {
        for (var k = 0u; k < p.num_rods; k++) {
            let c = rod_contact(k, x, reach);
            if c.hit {
                touch(stiffness, c.depth, c.n, d, c.vs, friction_pass);
            }
        }
    }
    if USES_BODIES {
        for (var k = 0u; k < p.num_bodies; k++) {
            let c = body_contact(k, x, reach);
            if c.hit {
                touch(stiffness, c.depth, c.n, d, c.vs, friction_pass);
            }
        }
    }
}

// The contacts' penalties, then their friction (core::cpu::vbd::contacts).
fn contacts(stiffness: f32, x: vec3<f32>, d: vec3<f32>) {
    each_contact(stiffness, x, d, false);
    if vbd_mu() <= 0.0 {
        return;
    }
    hess_n = hess;
    force_n = force_acc;
    each_contact(stiffness, x, d, true);
}

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

// The particle's inertia, start and displacement so far (block_begin's).
var<private> vbd_inertia: f32;
var<private> vbd_x0: vec3<f32>;
var<private> vbd_moved: vec3<f32>;

// Particle i's block and force over its row's springs, inertia first (core::cpu::vbd::
// block_step up to the contacts); false for a held particle (no step).
fn block_begin(i: u32) -> bool {
    let x4 = aux1[world_base + i];
    if held(i, x4.w) {
        return false;
    }
    let h = p.dt;
    let x0 = x4.xyz;
    let inertia = mass_of(x4.w) / (h * h);
    let moved = aux2[world_base + i].xyz;
    var f = (aux0[world_base + i].xyz * h - moved) * inertia;
    hess = array<f32, 6>(inertia, inertia, inertia, 0.0, 0.0, 0.0);
    let r = slot_row(i);
    for (var s = 0u; s < r.count; s++) {
        let slot = row_slot(i, r, s);
        let other = slot_other(slot);
        if other < 0 || slot.ks <= 0.0 {
            continue;
        }
        let j = u32(other);
        let u = moved - aux2[world_base + j].xyz;
        let dx = (x0 - aux1[world_base + j].xyz) + u;
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
        add_block(a * scale, b * scale, n);
    }
    force_acc = f;
    vbd_inertia = inertia;
    vbd_x0 = x0;
    vbd_moved = moved;
    return true;
}

// The block finished with the colliders' contacts and solved: the new displacement.
fn block_end() -> vec3<f32> {
    contacts(vbd_inertia * CONTACT_STIFFNESS, vbd_x0 + vbd_moved, vbd_moved);
    let step = solve_sym3(hess[0], hess[1], hess[2], hess[3], hess[4], hess[5], force_acc);
    return vbd_moved + step;
}
