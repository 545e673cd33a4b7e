"""Fit a cloth's stretch and bend stiffness and its damping to a target drape, by the
gradients of a recorded run (``clothlab.Sim(grad=True)``, docs/gradients.md).

The default scene (a cloth held at two corners swinging onto three spheres and the floor,
its strain limit on) at n = 16. The target: the positions after
``FRAMES`` frames with the default values. The fit starts every value 2× off — half the
target's (twice would pass the explicit stability limit the stiffnesses sum to) — and
descends on their logarithms (Adam), each step one run forward and one backward:

    python python/examples/fit_drape.py [--out loss.svg] [--steps 100] [--backend cpu-par]

It prints each step's loss and values and writes the loss's curve as an SVG. Exit status
0 when every value ends within 1 % of the target's.
"""

import argparse
import math
import os
import sys

import numpy as np

import clothlab

FRAMES = 40
NAMES = ["structural_stiffness", "bend_stiffness", "damping"]
TARGET = {"structural_stiffness": 0.45, "bend_stiffness": 0.05, "damping": 0.0005}


def run(sim: clothlab.Sim, values: dict) -> np.ndarray:
    """The positions after FRAMES frames from the scene's start with `values`."""
    sim.reset()
    sim.update(values)
    sim.reset_grad()
    sim.step(FRAMES)
    return sim.positions().astype(np.float64)


def svg(losses: list, path: str) -> None:
    """The loss by step, log scale, as a small SVG."""
    w, h, pad = 640, 360, 50
    logs = [math.log10(max(l, 1e-30)) for l in losses]
    lo, hi = min(logs), max(logs)
    hi = hi if hi > lo else lo + 1
    pts = " ".join(
        f"{pad + (w - 2 * pad) * k / max(len(logs) - 1, 1):.1f},{h - pad - (h - 2 * pad) * (v - lo) / (hi - lo):.1f}"
        for k, v in enumerate(logs)
    )
    steps = len(logs) - 1
    xticks = "".join(
        f'<text x="{pad + (w - 2 * pad) * k / max(steps, 1):.1f}" y="{h - pad + 16}" font-size="11" text-anchor="middle">{k}</text>'
        for k in range(0, steps + 1, max(steps // 4, 1))
    )
    ticks = xticks + "".join(
        f'<text x="{pad - 6}" y="{h - pad - (h - 2 * pad) * (e - lo) / (hi - lo) + 4:.1f}" font-size="11" text-anchor="end">1e{e}</text>'
        for e in range(math.ceil(lo), math.floor(hi) + 1)
    )
    # Written beside it and renamed: a stopped run leaves the old file whole.
    tmp = f"{path}.tmp"
    with open(tmp, "w") as f:
        f.write(
            f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}">'
            f'<rect width="{w}" height="{h}" fill="white"/>'
            f'<line x1="{pad}" y1="{h - pad}" x2="{w - pad}" y2="{h - pad}" stroke="black"/>'
            f'<line x1="{pad}" y1="{pad}" x2="{pad}" y2="{h - pad}" stroke="black"/>{ticks}'
            f'<text x="{w / 2}" y="{h - 12}" font-size="12" text-anchor="middle">gradient step</text>'
            f'<text x="{w / 2}" y="24" font-size="13" text-anchor="middle">fit_drape.py: the loss (half the mean squared distance to the target drape, m²)</text>'
            f'<polyline points="{pts}" fill="none" stroke="#1f77b4" stroke-width="2"/></svg>'
        )
    os.replace(tmp, path)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default="fit_drape_loss.svg")
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--backend", default="cpu-par")
    a = ap.parse_args()
    sim = clothlab.Sim(n=16, backend=a.backend, grad=True)
    target = run(sim, TARGET)
    n = len(target)
    theta = np.array([math.log(0.5 * TARGET[k]) for k in NAMES])
    m, v = np.zeros(3), np.zeros(3)
    lr, b1, b2 = 0.05, 0.9, 0.999
    losses = []
    for step in range(a.steps + 1):
        values = {k: float(math.exp(t)) for k, t in zip(NAMES, theta)}
        x = run(sim, values)
        r = x - target
        loss = 0.5 * float((r * r).sum()) / n  # half the mean squared distance
        losses.append(loss)
        off = max(abs(values[k] / TARGET[k] - 1) for k in NAMES)
        print(f"step {step:3d}  loss {loss:.3e}  " + "  ".join(f"{k} {values[k]:.6g}" for k in NAMES) + f"  (off {off:.2%})")
        if step == a.steps:
            break
        g = sim.backward(positions=(r / n).astype(np.float32))
        # d loss / d log value = value × d loss / d value.
        grad = np.array([g["params"][k] * values[k] for k in NAMES])
        m = b1 * m + (1 - b1) * grad
        v = b2 * v + (1 - b2) * grad * grad
        mh, vh = m / (1 - b1 ** (step + 1)), v / (1 - b2 ** (step + 1))
        theta -= lr * mh / (np.sqrt(vh) + 1e-12)
    svg(losses, a.out)
    print(f"loss curve: {a.out}")
    return 0 if off < 0.01 else 1


if __name__ == "__main__":
    sys.exit(main())
