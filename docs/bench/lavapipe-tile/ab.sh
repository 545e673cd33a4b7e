#!/usr/bin/env bash
# The optimized preset (A) against optimized+fusion=tile (B) on lavapipe / llvmpipe, per API
# and size, one round (B's shader compiles for about two minutes at its first dispatch,
# inside its run). Prints ns per particle-substep (GPU timestamps, median) and each run's
# wall time.
set -u
bin=${1:-./target/release/clothlab}
for n in 64 128 256; do
  for b in vulkan wgpu gl; do
    for v in A B; do
      x=""; [ $v = B ] && x="--set-variant fusion=tile"
      s=$(date +%s)
      # shellcheck disable=SC2086
      t=$("$bin" sim --backend $b --n $n --steps 32 $x 2>&1 | grep -m1 "time/substep" | sed 's/.*median (//; s/ ns.*//')
      echo "$n $b $v $t ns $(( $(date +%s) - s )) s"
    done
  done
done
