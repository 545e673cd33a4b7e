"""The backward pass against the forward pass (docs/gradients.md): the default scene, 60
frames, on cpu and cpu-par at n = 64 and 256, interleaved rounds. For each: the forward
run's time without a recording and with one, the backward pass's time, and the
recording's bytes a frame against the state's (positions and velocities in f32: 32 bytes
a particle). Prints one line per measurement; `python bench.py ROUNDS`.
"""

import sys
import time

import numpy as np

import clothlab

FRAMES = 60
rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 3
print("round backend n forward_s recorded_s backward_s backward/forward bytes_per_frame state_bytes")
for r in range(rounds):
    for n in (64, 256):
        for backend in ("cpu", "cpu-par"):
            plain = clothlab.Sim(n=n, backend=backend)
            t = time.perf_counter()
            plain.step(FRAMES)
            forward = time.perf_counter() - t
            sim = clothlab.Sim(n=n, backend=backend, grad=True)
            t = time.perf_counter()
            sim.step(FRAMES)
            recorded = time.perf_counter() - t
            x = sim.positions()
            t = time.perf_counter()
            sim.backward(positions=np.full_like(x, 1.0 / len(x)))
            backward = time.perf_counter() - t
            frames, nbytes = sim.recorded
            print(
                f"{r} {backend} {n} {forward:.3f} {recorded:.3f} {backward:.3f} {backward / forward:.1f} "
                f"{nbytes // frames} {32 * len(x)}",
                flush=True,
            )
