//! include: state, table, gather, window, spring_block, force_buffer, adjacency
//! worlds
// forces_springs — forces + springs fused (shared/spring_block.wgsl), each particle's force
// starting from the force buffer, where vertex_normals left the wind.
