// Per-substep statistics of the state (core::cpu::stats): the largest structural strain
// |L| / rest - 1 (each structural spring once, from its left or lower end: slots 1 and 3)
// and the kinetic energy 1/2 m |x - x*|² / dt². The substep's index comes in immediates
// (push constants), so every substep of a frame writes its own entry.

@group(0) @binding(0) var<uniform> p: StepParams;
@group(0) @binding(1) var<storage, read_write> pos: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> prev: array<vec4<f32>>;

struct StatsPush {
    substep: u32,
}
var<immediate> stats_push: StatsPush;
