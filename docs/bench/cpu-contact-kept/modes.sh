#!/usr/bin/env bash
# The same cells as ab.sh with the particle contact and with no self-contact (one binary):
# what the triangles' contact costs against them. Usage: modes.sh BIN
set -euo pipefail
B=$1
cells=(
  "heap64|--scene scenes/thin-heap.toml --steps 800"
  "heap128|--scene scenes/thin-heap.toml --n 128 --steps 320"
  "twist|--scene scenes/twist-triangles.toml --integrator vbd --set substeps=10 --set vbd_iterations=4 --steps 600"
  "stack|--scene scenes/stack.toml --steps 480"
)
for c in "${cells[@]}"; do
  name=${c%%|*} args=${c#*|}
  for be in cpu cpu-par; do
    for mode in triangles particles off; do
      # shellcheck disable=SC2086
      out=$($B sim $args --backend "$be" --set self_collision=$mode)
      echo "$name $be $mode $(echo "$out" | awk '/^wall time/{print $3}') $(echo "$out" | awk '/^substeps/{print $2}') $(echo "$out" | awk '/^crossings/{print $2}')"
    done
  done
done
