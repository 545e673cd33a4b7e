#!/usr/bin/env bash
# Interleaved: for each round, each cell, each binary in $BINS ("NAME=PATH ..."): time/substep (us).
set -uo pipefail
ROUNDS=${ROUNDS:-3}
[ -n "${LP:-}" ] && export LP_NUM_THREADS=$LP
cd /work/main
for r in $(seq 1 "$ROUNDS"); do
  while read -r name args; do
    [ -z "$name" ] && continue
    for nb in $BINS; do
      bn=${nb%%=*}; bin=${nb#*=}
      t=$($bin sim $args 2>/dev/null | awk '/^time\/substep/ {print $2}')
      echo "round $r $name $bn $t"
    done
  done <<< "$CELLS"
done
