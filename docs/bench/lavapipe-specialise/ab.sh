#!/usr/bin/env bash
# The default scene before the wave that added rods, bodies, Coulomb friction and motion
# (OLD: the release binary of 7015e92) against today's with the kernels compiled for the
# scene (NEW, the optimized preset: specialize=on) and without (NEW with
# --set-variant specialize=off), interleaved per cell, ROUNDS rounds; `time/substep` as
# `sim` prints it (the median of the run's substeps), µs.
# Usage: OLD=path/to/old/clothlab NEW=path/to/new/clothlab ROUNDS=3 ab.sh > runs.txt
set -euo pipefail
: "${OLD:?the binary before}" "${NEW:?the binary after}"
ROUNDS=${ROUNDS:-3}
for r in $(seq 1 "$ROUNDS"); do
  while read -r name args; do
    gpu=1; case "$name" in cpu*) gpu=0 ;; esac
    for which in OLD NEW NEWOFF; do
      if [ "$which" = NEWOFF ]; then
        [ $gpu = 1 ] || continue
        t=$("$NEW" sim $args --set-variant specialize=off 2>/dev/null | awk '/^time\/substep/ {print $2}')
      else
        bin=${!which}
        t=$("$bin" sim $args 2>/dev/null | awk '/^time\/substep/ {print $2}')
      fi
      echo "round $r $name $which $t"
    done
  done <<'CELLS'
vulkan-256 --backend vulkan --n 256 --steps 48
vulkan-512 --backend vulkan --n 512 --steps 32
wgpu-256 --backend wgpu --n 256 --steps 48
wgpu-512 --backend wgpu --n 512 --steps 32
gl-256 --backend gl --n 256 --steps 48
gl-512 --backend gl --n 512 --steps 32
cpu-512 --backend cpu --n 512 --steps 160
cpu-par-512 --backend cpu-par --n 512 --steps 160
CELLS
done
