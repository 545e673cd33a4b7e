#!/usr/bin/env bash
# The tiled substep before (OLD: every stage over the whole 32 × 32 region, the last stage
# stored into workgroup memory and written out after two more barriers) and after
# (NEW: each stage's invocations on its own points only, the last stage written out
# directly), beside `optimized`, on lavapipe / llvmpipe, interleaved per size and API,
# ROUNDS rounds. ns per particle-substep (median of the GPU timestamps over 32 substeps).
# usage: dense.sh OLD_BINARY NEW_BINARY
set -u
old=$1; new=$2; ROUNDS=${ROUNDS:-2}
t() { "$1" sim --backend "$2" --n "$3" --steps 32 "${@:4}" 2>&1 | grep -m1 "time/substep" | sed 's/.*median (//; s/ ns.*//'; }
for r in $(seq "$ROUNDS"); do
  for n in 32 64 128 256 512; do
    for b in vulkan wgpu gl; do
      echo "round $r n=$n $b optimized $(t "$new" $b $n) old-tile $(t "$old" $b $n --set-variant fusion=tile) new-tile $(t "$new" $b $n --set-variant fusion=tile) new-temporal $(t "$new" $b $n --set-variant fusion=tile --set-variant temporal=on)"
    done
  done
done
