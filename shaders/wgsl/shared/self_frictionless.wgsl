// The self-collision response without friction between particles (self_collide,
// self_collide_mesh): the recipe takes these without Coulomb's coefficients, and they
// carry no friction code (shared/self_friction.wgsl is the other side).
const FRICTION: bool = false;

fn rub(m: ptr<function, Mover>, e: vec3<f32>, d2: f32, sep: f32, share: f32, w: u32, hit: bool) {}
