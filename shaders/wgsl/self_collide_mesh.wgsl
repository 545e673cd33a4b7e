//! include: state, hash, hash_fn, self_frictionless, self_collide_walk, adjacency, self_collide_mesh_fn, cells
//! worlds
// self_collide_mesh — self_collide on a mesh (shared/self_collide_walk.wgsl): pairs of
// consecutive particles of the list, and a particle's neighbours are its springs, read
// from the table for the few entries within the thickness (core::cpu::self_collide::
// mesh_candidates). A kernel of its own so that a grid's response carries no table loop:
// on lavapipe a branch costs its body whether a lane takes it or not (2.4x the grid's
// response with the loop behind an `if`).
