#!/usr/bin/env bash
# Triangles against particles, interleaved: thin-heap at n = 64 and 128, stack at its size.
cd /work/main
B=target/release/clothlab
for round in 1 2 3; do
  for case in "thin-heap 64" "thin-heap 128" "stack -"; do
    set -- $case
    for mode in triangles particles; do
      nargs=(); [ "$2" != "-" ] && nargs=(--n $2)
      out=$(NODEVICE_SELECT=1 $B sim --scene scenes/$1.toml "${nargs[@]}" --backend cpu-par --steps 320 --set self_collision=$mode 2>&1)
      echo "== $round $1 $2 $mode"
      echo "$out" | grep -E "^  [a-z_+ ]+ +[0-9.]+ " 
      echo "$out" | grep -E "crossings  "
    done
  done
done
