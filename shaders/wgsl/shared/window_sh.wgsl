// Subgroup shuffles for the blocked gathers (`neighbours=shuffle`, the warp-shuffle idiom
// of CUDA): the lanes of a subgroup that hold consecutive blocks of a row pass each other
// the points of their windows instead of loading them again. A lane checks that its
// neighbour really holds the block before (after) its own — same row, next block id —
// so any mapping of invocations to lanes is safe; where it does not (the subgroup's
// first and last lane, a row's first and last block) the kernel loads the point.
// Every call is made in uniform control flow (before any branch on the lane).

var<private> sh_left: bool;
var<private> sh_right: bool;

fn window_start(b: u32, per_row: u32) {
    // The lane index and the subgroup's size without the builtins, so that the kernel's
    // entry point is the same in both flavors (every lane is active here).
    let lane = subgroupExclusiveAdd(1u);
    let size = subgroupAdd(1u);
    let lb = subgroupShuffleUp(b, 1u);
    let rb = subgroupShuffleDown(b, 1u);
    sh_left = lane > 0u && lb + 1u == b && b % per_row != 0u;
    sh_right = lane + 1u < size && rb == b + 1u && (b + 1u) % per_row != 0u;
}

fn have_left() -> bool {
    return sh_left;
}

fn have_right() -> bool {
    return sh_right;
}

fn from_left3(v: vec3<f32>) -> vec3<f32> {
    return subgroupShuffleUp(v, 1u);
}

fn from_right3(v: vec3<f32>) -> vec3<f32> {
    return subgroupShuffleDown(v, 1u);
}

fn from_left4(v: vec4<f32>) -> vec4<f32> {
    return subgroupShuffleUp(v, 1u);
}

fn from_right4(v: vec4<f32>) -> vec4<f32> {
    return subgroupShuffleDown(v, 1u);
}
