//! include: table, stats, particle_stats, atomic_cas, adjacency
// stats_atomic — per particle, reduced with atomics (the naive way): atomicMax on the
// strain's bits (a non-negative float orders like its bits) and a float atomic add of the
// energy into the substep's entry.
@group(0) @binding(17) var<storage, read_write> stats_max: array<atomic<u32>>;
@group(0) @binding(18) var<storage, read_write> accum: array<AtomicF32>;

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let i = flat_id(id, groups);
    if i >= p.num_particles {
        return;
    }
    let v = particle_stats(i);
    atomicMax(&stats_max[stats_push.substep], bitcast<u32>(v.x));
    atomic_add_f32(stats_push.substep, v.y);
}
