//! include: state, hash, hash_fn, self_frictionless, self_collide_grid, self_collide_walk, cells
//! worlds
// self_collide — per pair of grid neighbours (i, i + 1) of a row: each pushed out of every
// candidate closer than the thickness, the push added to its velocity (Δx/dt); into
// pos_out, vel in place (core::cpu::self_collide::self_collide_at, per particle there).
// The two share one walk over the rows of cells that either's sphere reaches, when their
// cells are neighbours (almost always: grid neighbours lie about a spacing apart): half the
// rows' reads, and each entry read once for both. Each particle's contacts are its twin's
// (push), summed in fixed point: in any order, the same bits. The walk is
// shared/self_collide_walk.wgsl (self_collide_mesh.wgsl is the mesh's).
