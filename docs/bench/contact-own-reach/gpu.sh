#!/usr/bin/env bash
# The contact between triangles on raw Vulkan (lavapipe), A against B, one round each:
# ms a substep (the `substep` row's median) and a frame of `clothlab sim` with
# triangles, and with the particle contact for scale. Usage: gpu.sh A_BIN B_BIN
set -euo pipefail
A=$1 B=$2
cells=(
  "heap64|--scene scenes/thin-heap.toml --steps 480"
  "twist|--scene scenes/twist-triangles.toml --integrator vbd --set substeps=10 --set vbd_iterations=4 --steps 200"
)
for c in "${cells[@]}"; do
  name=${c%%|*} args=${c#*|}
  for run in "A triangles" "B triangles" "B particles"; do
    set -- $run
    bin=$A; [ "$1" = B ] && bin=$B
    # shellcheck disable=SC2086
    out=$(LP_NUM_THREADS=0 $bin sim $args --backend vulkan --set self_collision=$2)
    sub=$(echo "$out" | awk '$1 == "substep" {print $2 / 1000}')
    frame=$(echo "$out" | awk '$1 == "frame" {print $2 / 1000}')
    echo "$name vulkan $1 $2 substep_ms=$sub frame_ms=$frame"
  done
done
