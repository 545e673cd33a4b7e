// chain — the API-overhead micro-benchmark of `clothlab bench`, not part of the step:
// every invocation adds 1 to its element. k dispatches in a row, each depending on the
// one before (a barrier between), leave k in every element, so the benchmark can check
// that each dispatch ran and saw its predecessor's writes.
@group(0) @binding(0) var<storage, read_write> data: array<u32>;

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < arrayLength(&data) {
        data[id.x] = data[id.x] + 1u;
    }
}
