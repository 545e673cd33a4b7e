//! include: state
//! worlds
// pins — per moving pin (core::pins::drive): the particle put where its group's pose has
// it at this substep's start (or end: core::pins::at_substep_end), with the pose's velocity. The frame's poses are
// written once per frame, a block of MAX_PIN_GROUPS per substep (a batch's: per substep,
// a block per world, world after world); the substep's first block comes in immediates.
@group(0) @binding(32) var<storage, read> pin_slots: array<PinSlot>;
@group(0) @binding(33) var<storage, read> pin_poses: array<PinPose>;

struct PinsPush {
    substep: u32,
}
var<immediate> pins_push: PinsPush;

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let k = flat_id(id, groups);
    if k >= arrayLength(&pin_slots) {
        return;
    }
    let s = pin_slots[k];
    // The one unused element of a cloth without moving pins names no particle.
    if s.index >= num_particles() {
        return;
    }
    let pose = pin_poses[(pins_push.substep + world_index) * MAX_PIN_GROUPS + min(s.group, MAX_PIN_GROUPS - 1u)];
    // (c0·r.x + c1·r.y) + c2·r.z, then + translation: the twin's order (PinPose::place).
    let arm = pose.cols[0].xyz * s.rest.x + pose.cols[1].xyz * s.rest.y + pose.cols[2].xyz * s.rest.z;
    let x = arm + pose.translation.xyz;
    let v = surface_vel(pose.velocity.xyz, pose.spin.xyz, arm);
    let i = world_base + s.index;
    pos[i] = vec4<f32>(x, pos[i].w);
    vel[i] = vec4<f32>(v, 0.0);
}
