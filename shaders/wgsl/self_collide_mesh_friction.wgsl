//! include: state, hash, hash_fn, hash_vel, self_friction, self_collide_walk, adjacency, self_collide_mesh_fn, cells
//! worlds
// self_collide_mesh_friction — self_collide_mesh (self_collide_mesh.wgsl) with Coulomb
// friction at its contacts (shared/self_friction.wgsl): the recipe's response on a mesh
// when the parameters have Coulomb's coefficients.
