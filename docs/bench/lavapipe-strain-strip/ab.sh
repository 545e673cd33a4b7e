#!/usr/bin/env bash
# The strain pass down strips (`strain_counts=strip`, the optimized preset's on a CPU
# adapter) against the pass that counts inline and against 7015e92 (before rods, bodies,
# Coulomb friction and moving colliders), interleaved per cell, ROUNDS rounds;
# `time/substep` as `sim` prints it (the median of the run's substeps), µs. The cells come
# from CELLS: each line `name binaries args`, binaries the comma-separated ones that run it
# (A7015 only where its scenes existed; INLINE and STRIP only on the GPU backends).
#   cells.txt: the sizes and the scenes, 3 rounds (runs.txt);
#   cells-issue.txt: the issue's table, the CPU's cells too, 7 rounds (runs7.txt: this VM
#   switches between a fast and a slow phase, which 3 rounds do not average out; that run
#   took STRIP as the preset's default, which on lavapipe is the strips, and named the
#   CPU's today STRIP too, where this file now says TODAY).
# Usage: A7015=… NEW=… CELLS=cells.txt ROUNDS=3 ab.sh > runs.txt;
#   python3 paired.py runs.txt A7015 (each round's ratios), or ../lavapipe-strain-skip/medians.py
set -uo pipefail
: "${A7015:?}" "${NEW:?}"
here=$(cd "$(dirname "$0")" && pwd)
cells=$here/${CELLS:-cells.txt}
ROUNDS=${ROUNDS:-3}
cd "$here/../../.."
for r in $(seq 1 "$ROUNDS"); do
  while read -r name bins args; do
    for which in ${bins//,/ }; do
      case $which in
        A7015) bin=$A7015; x="" ;;
        INLINE) bin=$NEW; x="--set-variant strain_counts=inline" ;;
        STRIP) bin=$NEW; x="--set-variant strain_counts=strip" ;;
        TODAY) bin=$NEW; x="" ;;
      esac
      # shellcheck disable=SC2086
      t=$("$bin" sim $args $x 2>/dev/null | awk '/^time\/substep/ {print $2}')
      echo "round $r $name $which $t"
    done
  done < "$cells"
done
