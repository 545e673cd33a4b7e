// What forces_springs' particles start from (shared/spring_block.wgsl): the force buffer,
// where the normals kernel of the substep before left the wind.

// The force of particle (c, row) (particle 0's, unused, off the grid: every lane loads).
fn buffered(c: u32, row: u32) -> vec3<f32> {
    return force[world_base + select(0u, row * p.n + c, c < p.n && row < p.n)].xyz;
}

// Block (row, c0): its particles' forces (the window's positions are not needed here).
fn block_base(row: u32, c0: u32, u: array<vec3<f32>, 6>, r: array<vec3<f32>, 6>, d: array<vec3<f32>, 6>) -> Base4 {
    return Base4(buffered(c0, row), buffered(c0 + 1u, row), buffered(c0 + 2u, row), buffered(c0 + 3u, row));
}

// Particle i (on the grid).
fn particle_base(i: u32) -> vec3<f32> {
    return force[world_base + i].xyz;
}
