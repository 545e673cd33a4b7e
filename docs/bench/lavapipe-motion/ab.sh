#!/usr/bin/env bash
# The cost of motion (issue 45): the spinning-sphere scene with its sphere spinning (A)
# and still (B), interleaved A B A B, per backend and grid size: `sim`'s median
# time per substep (kernel timestamps on the GPU APIs) and its frame median.
# Run from the repository root after `cargo build --release`.
set -euo pipefail
bin=target/release/clothlab
still=$(mktemp --suffix .toml)
sed 's/^motion = .*$//' scenes/spinning-sphere.toml > "$still"
for round in 1 2 3; do
  for n in 128 256; do
    for backend in cpu-par wgpu vulkan gl; do
      for which in moving still; do
        scene=scenes/spinning-sphere.toml
        [ "$which" = still ] && scene=$still
        out=$($bin sim --scene "$scene" --backend "$backend" --n "$n" --steps 320 2>&1)
        sub=$(echo "$out" | awk '/^time\/substep/ {print $2}')
        frame=$(echo "$out" | awk '$1 == "frame" {print $2}')
        rec=$(echo "$out" | awk '$1 == "cpu" && $2 == "record" {print $3}')
        echo "round $round n $n $backend $which substep_us $sub frame_us $frame record_us ${rec:-0}"
      done
    done
  done
done
rm -f "$still"
