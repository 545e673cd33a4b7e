// Float addition into `accum` (declared by the kernel as array<AtomicF32>) with a
// compare-exchange loop on the bit pattern: WGSL has no float atomics. The build also
// emits every kernel that includes this file as `<kernel>_f32`, with atomic_f32.wgsl
// instead, for adapters with Features::SHADER_FLOAT32_ATOMIC.
alias AtomicF32 = atomic<u32>;

fn atomic_add_f32(idx: u32, v: f32) {
    var old = atomicLoad(&accum[idx]);
    loop {
        let new_bits = bitcast<u32>(bitcast<f32>(old) + v);
        let r = atomicCompareExchangeWeak(&accum[idx], old, new_bits);
        if r.exchanged {
            break;
        }
        old = r.old_value;
    }
}
