#!/usr/bin/env bash
# The thin heap at n = 256 for table.sh's rows: the thickness at 0.25 of the spacing as
# at n = 64 (thin-heap.toml's 4 mm is more than the 2.5 mm the contact takes at n = 256),
# 800 substeps on the CPU (the fall and the landing, as n = 64), 160 on Vulkan (the fall
# only: lavapipe takes seconds a substep). `heap256.sh BIN OUTDIR`, lines as table.sh's.
set -uo pipefail
B=$1 OUT=$2
mkdir -p "$OUT"
for be in cpu cpu-par vulkan; do
  steps=800; [ "$be" = vulkan ] && steps=160
  for mode in triangles particles off; do
    f="$OUT/heap256-$be-$mode.txt"
    timeout 1200 "$B" sim --scene scenes/thin-heap.toml --n 256 --set self_thickness=0.001 --steps $steps \
      --backend "$be" --set self_collision=$mode > "$f" 2>&1
    med=$(awk '/^time\/substep/{print $2}' "$f")
    tb=$(awk '$1=="tri_bounds"{print $2}' "$f")
    tc=$(awk '$1=="tri_contact"{print $2}' "$f")
    srch=$(awk '$1=="searches"{print $2, $9}' "$f")
    cr=$(awk '/^crossings/{print $2}' "$f")
    echo "heap256 $be $mode ${med:-?} ${tb:--} ${tc:--} ${srch:-- -} ${cr:-?} $steps"
  done
done
