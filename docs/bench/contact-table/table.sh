#!/usr/bin/env bash
# The contact between triangles beside the particle contact and no self-contact, every
# backend, one run a cell: `table.sh BIN OUTDIR` writes each run's `sim` report to
# OUTDIR/<scene>-<backend>-<mode>.txt and one line a cell to stdout:
# scene backend mode substep_median_us tri_bounds_us tri_contact_us searches partial crossings
set -uo pipefail
B=$1 OUT=$2
mkdir -p "$OUT"
cells=(
  "heap64|--scene scenes/thin-heap.toml --steps 800"
  "heap128|--scene scenes/thin-heap.toml --n 128 --steps 320"
  "heap256|--scene scenes/thin-heap.toml --n 256 --steps 160"
  "stack|--scene scenes/stack.toml --steps 480"
  "twist|--scene scenes/twist-triangles.toml --integrator vbd --set substeps=10 --set vbd_iterations=4 --steps 600"
)
for c in "${cells[@]}"; do
  name=${c%%|*} args=${c#*|}
  for be in cpu cpu-par vulkan wgpu gl; do
    for mode in triangles particles off; do
      f="$OUT/$name-$be-$mode.txt"
      # shellcheck disable=SC2086
      timeout 900 "$B" sim $args --backend "$be" --set self_collision=$mode > "$f" 2>&1
      med=$(awk '/^time\/substep/{print $2}' "$f")
      tb=$(awk '$1=="tri_bounds"{print $2}' "$f")
      tc=$(awk '$1=="tri_contact"{print $2}' "$f")
      srch=$(awk '$1=="searches"{print $2, $9}' "$f")
      cr=$(awk '/^crossings/{print $2}' "$f")
      echo "$name $be $mode ${med:-?} ${tb:--} ${tc:--} ${srch:-- -} ${cr:-?}"
    done
  done
done
