#!/usr/bin/env bash
# The strain pass down strips (`strain_counts=strip`, the optimized preset's on a CPU
# adapter) against the pass that counts inline and against 7015e92 (before rods, bodies,
# Coulomb friction and moving colliders), interleaved per cell, ROUNDS rounds;
# `time/substep` as `sim` prints it (the median of the run's substeps), µs. A7015 runs
# only the cells its scenes existed for.
# Usage: A7015=… NEW=… ROUNDS=3 ab.sh > runs.txt; python3 ../lavapipe-strain-skip/medians.py runs.txt A7015
set -uo pipefail
: "${A7015:?}" "${NEW:?}"
ROUNDS=${ROUNDS:-3}
cd "$(dirname "$0")/../../.."
for r in $(seq 1 "$ROUNDS"); do
  while read -r name old args; do
    for which in A7015 INLINE STRIP; do
      [ "$which" = A7015 ] && [ "$old" = no ] && continue
      case $which in
        A7015) bin=$A7015; x="" ;;
        INLINE) bin=$NEW; x="--set-variant strain_counts=inline" ;;
        STRIP) bin=$NEW; x="--set-variant strain_counts=strip" ;;
      esac
      # shellcheck disable=SC2086
      t=$("$bin" sim $args $x 2>/dev/null | awk '/^time\/substep/ {print $2}')
      echo "round $r $name $which $t"
    done
  done <<'CELLS'
vulkan-64 yes --backend vulkan --n 64 --steps 96
vulkan-128 yes --backend vulkan --n 128 --steps 64
vulkan-256 yes --backend vulkan --n 256 --steps 48
vulkan-512 yes --backend vulkan --n 512 --steps 32
wgpu-256 yes --backend wgpu --n 256 --steps 48
wgpu-512 yes --backend wgpu --n 512 --steps 32
gl-256 yes --backend gl --n 256 --steps 48
gl-512 yes --backend gl --n 512 --steps 32
heap-vulkan yes --backend vulkan --scene scenes/heap.toml --steps 48
meshheap-vulkan yes --backend vulkan --scene scenes/mesh-heap.toml --steps 48
body-vulkan no --backend vulkan --scene scenes/body-sphere.toml --steps 48
capsules-vulkan no --backend vulkan --scene scenes/capsules.toml --steps 48
sliding-vulkan no --backend vulkan --scene scenes/sliding-table.toml --steps 48
CELLS
done
