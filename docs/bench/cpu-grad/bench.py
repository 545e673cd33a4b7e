"""The CPU backward pass against the forward pass (docs/gradients.md): the default scene
(strain limit on, 16 substeps a frame), 20 frames, on cpu and cpu-par at n = 32 and 64,
under Verlet and implicit Euler. For each: the forward run's time without a recording and
with one (both after a first frame), and the backward pass's time (the f64 model's walk:
`clothlab_cpu::grad::Recording::backward`). Prints one line per measurement;
`python bench.py ROUNDS`.
"""

import sys
import time

import numpy as np

import clothlab

FRAMES = 20
rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 1
print("round integrator backend n forward_s recorded_s backward_s backward/forward")
for r in range(rounds):
    for n in (32, 64):
        for integrator in ("verlet", "implicit"):
            for backend in ("cpu", "cpu-par"):
                params = {"integrator": integrator}
                plain = clothlab.Sim(n=n, backend=backend, params=params)
                plain.step(1)
                t = time.perf_counter()
                plain.step(FRAMES)
                forward = time.perf_counter() - t
                sim = clothlab.Sim(n=n, backend=backend, params=params, grad=True)
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
                    f"{r} {integrator} {backend} {n} {forward:.3f} {recorded:.3f} {backward:.3f} "
                    f"{backward / forward:.1f}",
                    flush=True,
                )
