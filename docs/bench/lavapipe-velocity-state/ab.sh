#!/usr/bin/env bash
# Verlet's substep before and after the state kept velocities: OLD and NEW
# binaries interleaved (A B A B …), n = 512, the default scene: 160 substeps (10 frames) on
# cpu-par, 48 (3 frames) on the GPU backends (lavapipe takes ~0.18 s a substep there).
# Usage: OLD=path/to/old/clothlab NEW=path/to/new/clothlab ROUNDS=4 ab.sh > runs.txt
set -euo pipefail
: "${OLD:?the binary before}" "${NEW:?the binary after}"
ROUNDS=${ROUNDS:-4}
for r in $(seq 1 "$ROUNDS"); do
  for backend in cpu-par wgpu vulkan; do
    for which in OLD NEW; do
      bin=${!which}
      steps=160; [ "$backend" = cpu-par ] || steps=48
      t=$("$bin" sim --backend "$backend" --n 512 --steps "$steps" 2>/dev/null | awk '/^time\/substep/ {print $2}')
      echo "round $r $backend $which $t"
    done
  done
done
