//! include: state, table, gather, window, spring_block, wind_fn, face_wind, adjacency
//! worlds
// forces_springs_wind — forces + springs fused (shared/spring_block.wgsl), the wind of the
// faces around each particle computed here from the positions the gather loads anyway
// (shared/face_wind.wgsl): the force buffer is not read, and no normals kernel needs to run
// between two substeps (`normals=frame`: the vertex normals once per frame, for drawing).
