// Shared structs and pure functions. Every struct mirrors a #[repr(C)] type of
// clothlab-core; shaders/build.rs checks their sizes and field offsets.

struct StepParams {
    gravity: vec4<f32>,
    wind: vec4<f32>,
    grab_target: vec4<f32>,
    dt: f32,
    damping: f32,
    air_drag: f32,
    particle_mass: f32,
    floor_y: f32,
    margin: f32,
    friction: f32,
    strain_limit: f32,
    n: u32,
    num_spheres: u32,
    num_boxes: u32,
    grab_index: i32,
}

struct SpringSlot {
    neighbor: i32,
    rest: f32,
    ks: f32,
    kd: f32,
}

struct Spring {
    a: u32,
    b: u32,
    rest: f32,
    ks: f32,
    kd: f32,
    kind: u32,
}

struct Tether {
    pin: i32,
    rest: f32,
}

struct InteriorSlots {
    slots: array<SpringSlot, 12>,
    enabled: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

struct Sphere {
    center: vec3<f32>,
    radius: f32,
}

struct Aabb {
    min: vec4<f32>,
    max: vec4<f32>,
}

const WORKGROUP: u32 = 64u;
const SLOTS: u32 = 12u;
const STRAIN_SLOTS: u32 = 8u;
const FACE_SLOTS: u32 = 6u;
const TETHER_SLOTS: u32 = 2u;
// Particles per invocation of the blocked kernels (clothlab_shaders::recipe::BLOCK).
const BLOCK: u32 = 4u;

// (row, first column) of the BLOCK consecutive particles block b of an n × n grid covers:
// n · ceil(n / BLOCK) blocks, a row's last one cut short when BLOCK does not divide n.
fn block_origin(b: u32, n: u32) -> vec2<u32> {
    let per_row = (n + BLOCK - 1u) / BLOCK;
    let row = b / per_row;
    return vec2<u32>(row, (b - row * per_row) * BLOCK);
}

// core::cpu::strain_limit::STRAIN_AIM
const STRAIN_AIM: f32 = 0.95;

// Force on end a of a spring with l = x_a - x_b and dv = (v_a - v_b) dt
// (core::cpu::springs::spring_force).
fn spring_force(l: vec3<f32>, dv: vec3<f32>, s: SpringSlot, inv_dt: f32) -> vec3<f32> {
    let len = length(l);
    if len <= 1.17549435e-38 {
        return vec3<f32>(0.0);
    }
    let dir = l * (1.0 / len);
    return -(s.ks * (len - s.rest) + (s.kd * inv_dt) * dot(dv, dir)) * dir;
}

// New previous position after a contact with a surface of unit normal nrm
// (core::cpu::integrate::contact_prev).
fn contact_prev(x: vec3<f32>, prev: vec3<f32>, nrm: vec3<f32>, friction: f32) -> vec3<f32> {
    let v = x - prev;
    let vn = dot(v, nrm);
    let vt = v - vn * nrm;
    let v_new = vt * (1.0 - friction) + max(vn, 0.0) * nrm;
    return x - v_new;
}

// Invocation index of a 1-D job dispatched as a 2-D grid of workgroups (one dimension
// holds at most 65535 workgroups).
fn flat_id(id: vec3<u32>, groups: vec3<u32>) -> u32 {
    return id.x + id.y * groups.x * WORKGROUP;
}

// core's Vec3::normalize_or_zero.
fn normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    let rcp = 1.0 / length(v);
    if rcp > 0.0 && rcp <= 3.40282347e38 {
        return v * rcp;
    }
    return vec3<f32>(0.0);
}
