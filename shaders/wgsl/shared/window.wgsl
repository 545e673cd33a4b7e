// How a blocked gather gets the points of its window that the lanes beside it hold (the
// columns left and right of its own four): here, by loading them. The build emits every
// kernel that includes this file as `<kernel>_sh` with shared/window_sh.wgsl instead,
// which passes them between the lanes of a subgroup (`neighbours=shuffle`).

fn window_start(b: u32, per_row: u32) {}

// Whether the lane on the left (right) holds the block before (after) this one in the row.
fn have_left() -> bool {
    return false;
}

fn have_right() -> bool {
    return false;
}

// What the lane on the left (right) passes of its `v` (here: nothing, `v` back unused).
fn from_left3(v: vec3<f32>) -> vec3<f32> {
    return v;
}

fn from_right3(v: vec3<f32>) -> vec3<f32> {
    return v;
}

fn from_left4(v: vec4<f32>) -> vec4<f32> {
    return v;
}

fn from_right4(v: vec4<f32>) -> vec4<f32> {
    return v;
}
