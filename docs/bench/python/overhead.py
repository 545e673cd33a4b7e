"""Stepping through Python against the command line, interleaved: `clothlab sim` (its
printed wall time: the frames' step calls alone) and `clothlab.Sim.step(frames)` (timed
around the one call), on the same scene, backend and size, alternating for ROUNDS rounds;
then `positions()` of a 512 × 512 cloth. Prints a Markdown table of medians, with each
side's spread between rounds (the A-vs-A noise a difference must stand out of).

    PYTHONPATH=<folder with the clothlab package> python3 docs/bench/python/overhead.py BINARY
"""

import re
import statistics
import subprocess
import sys
import time

import clothlab

BIN = sys.argv[1] if len(sys.argv) > 1 else "target/release/clothlab"
ROUNDS = 5
CASES = [("cpu-par", 128, 100), ("vulkan", 128, 100), ("cpu-par", 512, 10), ("vulkan", 512, 10)]


def cli(backend, n, frames):
    out = subprocess.run(
        [BIN, "sim", "--backend", backend, "--n", str(n), "--steps", str(16 * frames)],
        check=True, capture_output=True, text=True,
    ).stdout
    return float(re.search(r"wall time\s+([0-9.]+) s", out).group(1))


def py(backend, n, frames):
    sim = clothlab.Sim(n=n, backend=backend)
    t = time.perf_counter()
    sim.step(frames=frames)
    dt = time.perf_counter() - t
    sim.close()
    return dt


def spread(xs):
    return (max(xs) - min(xs)) / statistics.median(xs) * 100


print(f"| backend | n | frames | `clothlab sim` median s (spread) | `Sim.step` median s (spread) | Python / CLI |")
print("|---|---:|---:|---:|---:|---:|")
for backend, n, frames in CASES:
    a, b = [], []
    for _ in range(ROUNDS):
        a.append(cli(backend, n, frames))
        b.append(py(backend, n, frames))
    ma, mb = statistics.median(a), statistics.median(b)
    print(f"| {backend} | {n} | {frames} | {ma:.3f} ({spread(a):.1f} %) | {mb:.3f} ({spread(b):.1f} %) | {mb / ma:.3f} |", flush=True)

print()
print("| backend | n | `positions()` median ms | min ms |")
print("|---|---:|---:|---:|")
for backend in ["cpu-par", "vulkan", "wgpu", "gl"]:
    sim = clothlab.Sim(n=512, backend=backend)
    sim.step(frames=1)
    ts = []
    for _ in range(20):
        t = time.perf_counter()
        x = sim.positions()
        ts.append((time.perf_counter() - t) * 1e3)
    assert x.shape == (512 * 512, 3)
    print(f"| {backend} | 512 | {statistics.median(ts):.2f} | {min(ts):.2f} |", flush=True)
    sim.close()
