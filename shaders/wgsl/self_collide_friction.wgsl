//! include: state, hash, hash_fn, hash_vel, self_friction, self_collide_grid, self_collide_walk, cells
//! worlds
// self_collide_friction — self_collide (self_collide.wgsl) with Coulomb friction at its
// contacts (shared/self_friction.wgsl): the recipe's response when the parameters have
// Coulomb's coefficients (core::cpu::self_collide::self_collide_at, its friction).
