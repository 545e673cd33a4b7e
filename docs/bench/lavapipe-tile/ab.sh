#!/usr/bin/env bash
# The optimized preset (A) against optimized+fusion=tile (B) on lavapipe / llvmpipe, per API
# and size, A and B interleaved, two rounds. Prints round, size, API, A|B, ns per
# particle-substep (GPU timestamps, median over the run's substeps) and the run's wall time.
set -u
bin=${1:-./target/release/clothlab}
for r in 1 2; do
  for n in 32 64 128 256 512; do
    for b in vulkan wgpu gl; do
      for v in A B; do
        x=""; [ $v = B ] && x="--set-variant fusion=tile"
        s=$(date +%s)
        # shellcheck disable=SC2086
        t=$("$bin" sim --backend $b --n $n --steps 32 $x 2>&1 | grep -m1 "time/substep" | sed 's/.*median (//; s/ ns.*//')
        echo "$r $n $b $v $t ns $(( $(date +%s) - s )) s"
      done
    done
  done
done
