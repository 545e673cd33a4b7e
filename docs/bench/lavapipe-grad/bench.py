"""The GPU backward pass against the forward pass (docs/gradients.md): the default scene
(strain limit on, 16 substeps a frame), 20 frames, on vulkan, wgpu and gl at n = 32 and
64. For each: the forward run's time without a recording and with one (both after a
first frame that builds the kernels), and the backward pass's time (the adjoint kernels
walked from the host: `clothlab_engine::grad::KernelWalk`). Prints one line per
measurement; `python bench.py ROUNDS`.
"""

import sys
import time

import numpy as np

import clothlab

FRAMES = 20
rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 1
print("round backend n forward_s recorded_s backward_s backward/forward")
for r in range(rounds):
    for n in (32, 64):
        for backend in ("vulkan", "wgpu", "gl"):
            plain = clothlab.Sim(n=n, backend=backend)
            plain.step(1)
            t = time.perf_counter()
            plain.step(FRAMES)
            forward = time.perf_counter() - t
            sim = clothlab.Sim(n=n, backend=backend, grad=True)
            sim.step(1)
            sim.reset_grad()
            t = time.perf_counter()
            sim.step(FRAMES)
            recorded = time.perf_counter() - t
            x = sim.positions()
            t = time.perf_counter()
            sim.backward(positions=np.full_like(x, 1.0 / len(x)))
            backward = time.perf_counter() - t
            print(
                f"{r} {backend} {n} {forward:.3f} {recorded:.3f} {backward:.3f} {backward / forward:.1f}",
                flush=True,
            )
