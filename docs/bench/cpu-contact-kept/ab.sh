#!/usr/bin/env bash
# The contact between triangles with the kept pairs (B) against the search every substep
# (A: the commit before, or the same binary with search_margin=0), interleaved rounds:
# wall time of `clothlab sim` per scene and backend. Usage: ab.sh A_BIN B_BIN ROUNDS
set -euo pipefail
A=$1 B=$2 R=${3:-3}
cells=(
  "heap64|--scene scenes/thin-heap.toml --steps 800"
  "heap128|--scene scenes/thin-heap.toml --n 128 --steps 320"
  "twist|--scene scenes/twist-triangles.toml --integrator vbd --set substeps=10 --set vbd_iterations=4 --steps 600"
  "stack|--scene scenes/stack.toml --steps 480"
)
for r in $(seq "$R"); do
  for c in "${cells[@]}"; do
    name=${c%%|*} args=${c#*|}
    for be in cpu cpu-par; do
      for ab in A B; do
        bin=$A; [ "$ab" = B ] && bin=$B
        # shellcheck disable=SC2086
        out=$($bin sim $args --backend "$be")
        wall=$(echo "$out" | awk '/^wall time/{print $3}')
        sub=$(echo "$out" | awk '/^substeps/{print $2}')
        srch=$(echo "$out" | awk '/^  searches/{print $2, $9}')
        echo "$r $name $be $ab $wall $sub ${srch:-- -}"
      done
    done
  done
done
