// The velocities before the self-collision response, by particle (aux0, dead by then):
// hash_scatter copies them there with Coulomb friction, and the response reads its
// contacts' velocities from the copy, since it writes vel in place
// (core::cpu::self_collide::HashBuffers::vel_copy).
@group(0) @binding(24) var<storage, read_write> vel_copy: array<vec4<f32>>;
