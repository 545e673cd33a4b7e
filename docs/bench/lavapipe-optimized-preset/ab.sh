#!/usr/bin/env bash
# The optimized preset before (A: normals every substep, colliders in storage, neighbours
# loaded) and after the preset became the ladder's top (B: the ladder's top), A B per API, interleaved, three rounds.
# Prints ns per particle-substep (GPU timestamps, median of 160 substeps).
set -euo pipefail
bin=${1:-./target/release/clothlab}
for r in 1 2 3; do
  for v in A B; do
    if [ $v = A ]; then x="--set-variant normals=gather --set-variant colliders=storage --set-variant neighbours=load"; else x=""; fi
    for b in wgpu vulkan; do
      # shellcheck disable=SC2086
      t=$("$bin" sim --backend $b --n 512 --steps 160 $x 2>&1 | grep -m1 "time/substep" | sed 's/.*median (//; s/ ns.*//')
      echo "$r $v $b $t"
    done
  done
done
