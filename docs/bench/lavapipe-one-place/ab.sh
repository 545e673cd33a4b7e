#!/usr/bin/env bash
# The shape's refactor (rows that say how they run, StepParams written once, the mesh
# module split) against the code before it: OLD and NEW binaries interleaved (A B A B …),
# the default scene, each API's optimized preset at n = 128 and 256 (48 substeps) and the
# serial CPU at n = 512 (160 substeps); `time/substep` as `sim` prints it (the median of
# the run's substeps).
# Usage: OLD=path/to/old/clothlab NEW=path/to/new/clothlab ROUNDS=3 ab.sh > runs.txt
set -euo pipefail
: "${OLD:?the binary before}" "${NEW:?the binary after}"
ROUNDS=${ROUNDS:-3}
for r in $(seq 1 "$ROUNDS"); do
  for cell in "cpu 512 160" "vulkan 128 48" "vulkan 256 48" "wgpu 128 48" "wgpu 256 48" "gl 128 48" "gl 256 48"; do
    set -- $cell
    for which in OLD NEW; do
      bin=${!which}
      t=$("$bin" sim --backend "$1" --n "$2" --steps "$3" 2>/dev/null | awk '/^time\/substep/ {print $2}')
      echo "round $r $1 $2 $which $t"
    done
  done
done
