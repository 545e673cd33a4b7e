// Float addition into `accum` with float atomics (Features::SHADER_FLOAT32_ATOMIC).
alias AtomicF32 = atomic<f32>;

fn atomic_add_f32(idx: u32, v: f32) {
    atomicAdd(&accum[idx], v);
}
