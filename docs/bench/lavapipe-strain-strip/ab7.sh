#!/usr/bin/env bash
# The issue's table: the default scene, 7015e92 (before rods, bodies, Coulomb friction and
# moving colliders) against today's optimized preset (the strain pass down strips on
# lavapipe) and today's with the pass counting inline, interleaved per cell, ROUNDS rounds
# (7: this VM switches between a fast and a slow phase, which 3 rounds do not average out);
# the CPU cells (unchanged code: no strips there) against 7015e92 only. `time/substep`
# as `sim` prints it (the median of the run's substeps), µs.
# Usage: A7015=… NEW=… ROUNDS=7 ab7.sh > runs7.txt; python3 ../lavapipe-strain-skip/medians.py runs7.txt A7015
set -uo pipefail
: "${A7015:?}" "${NEW:?}"
ROUNDS=${ROUNDS:-7}
cd "$(dirname "$0")/../../.."
for r in $(seq 1 "$ROUNDS"); do
  while read -r name gpu args; do
    for which in A7015 INLINE STRIP; do
      [ "$which" = INLINE ] && [ "$gpu" = no ] && continue
      case $which in
        A7015) bin=$A7015; x="" ;;
        INLINE) bin=$NEW; x="--set-variant strain_counts=inline" ;;
        STRIP) bin=$NEW; x="" ;;
      esac
      # shellcheck disable=SC2086
      t=$("$bin" sim $args $x 2>/dev/null | awk '/^time\/substep/ {print $2}')
      echo "round $r $name $which $t"
    done
  done <<'CELLS'
vulkan-256 yes --backend vulkan --n 256 --steps 48
vulkan-512 yes --backend vulkan --n 512 --steps 32
wgpu-256 yes --backend wgpu --n 256 --steps 48
wgpu-512 yes --backend wgpu --n 512 --steps 32
gl-256 yes --backend gl --n 256 --steps 48
gl-512 yes --backend gl --n 512 --steps 32
cpu-512 no --backend cpu --n 512 --steps 32
cpupar-512 no --backend cpu-par --n 512 --steps 64
CELLS
done
