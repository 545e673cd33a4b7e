#!/usr/bin/env bash
# OLD NEW interleaved per cell, ROUNDS rounds; time/substep as sim prints it.
set -euo pipefail
ROUNDS=${ROUNDS:-3}
for r in $(seq 1 "$ROUNDS"); do
  while read -r name args; do
    for which in OLD NEW; do
      bin=${!which}
      t=$($bin sim $args 2>/dev/null | awk '/^time\/substep/ {print $2}')
      echo "round $r $name $which $t"
    done
  done <<'CELLS'
cpu-512 --backend cpu --n 512 --steps 160
vulkan-128 --backend vulkan --n 128 --steps 48
vulkan-256 --backend vulkan --n 256 --steps 48
wgpu-256 --backend wgpu --n 256 --steps 48
gl-128 --backend gl --n 128 --steps 48
gl-256 --backend gl --n 256 --steps 48
capsules-vulkan --backend vulkan --scene scenes/capsules.toml --steps 48
capsules-cpu --backend cpu --scene scenes/capsules.toml --steps 96
bodysphere-vulkan --backend vulkan --scene scenes/body-sphere.toml --steps 48
vbd-heap-vulkan --backend vulkan --scene scenes/heap.toml --integrator vbd --steps 32
CELLS
done
