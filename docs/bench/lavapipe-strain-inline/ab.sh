#!/usr/bin/env bash
# The strain pass counting for itself (`strain_counts=inline`, now in the optimized preset)
# against the count dispatch, interleaved per cell, ROUNDS rounds; `time/substep` as `sim`
# prints it (the median of the run's substeps), µs. Binaries: A7015 (7015e92, before rods,
# bodies, Coulomb friction and moving colliders), HEAD (the commit before the change), NEW
# (the change) and NEWDISP (the change with --set-variant strain_counts=dispatch).
# Usage: A7015=… HEAD=… NEW=… ROUNDS=3 ab.sh > runs.txt;
#   python3 ../lavapipe-strain-skip/medians.py runs.txt A7015
set -uo pipefail
: "${A7015:?}" "${HEAD:?}" "${NEW:?}"
ROUNDS=${ROUNDS:-3}
cd "$(dirname "$0")/../../.."
for r in $(seq 1 "$ROUNDS"); do
  while read -r name args; do
    for which in A7015 HEAD NEW NEWDISP; do
      bin=${!which:-$NEW}; x=""
      [ "$which" = NEWDISP ] && x="--set-variant strain_counts=dispatch"
      # shellcheck disable=SC2086
      t=$("$bin" sim $args $x 2>/dev/null | awk '/^time\/substep/ {print $2}')
      echo "round $r $name $which $t"
    done
  done <<'CELLS'
vulkan-256 --backend vulkan --n 256 --steps 48
vulkan-512 --backend vulkan --n 512 --steps 32
wgpu-256 --backend wgpu --n 256 --steps 48
wgpu-512 --backend wgpu --n 512 --steps 32
gl-256 --backend gl --n 256 --steps 48
gl-512 --backend gl --n 512 --steps 32
heap-vulkan --backend vulkan --scene scenes/heap.toml --steps 48
meshheap-vulkan --backend vulkan --scene scenes/mesh-heap.toml --steps 48
CELLS
done
