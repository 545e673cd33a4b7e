#!/usr/bin/env bash
# The cost of moving pins (issue 45): the cloth-twist scene without self-collision, its
# two pinned strips turning (A) and held still (B: the same [[pins]] without a motion),
# interleaved A B A B, per backend and grid size: `sim`'s median time per substep
# (kernel timestamps on the GPU APIs), its frame median and the `pins` kernel's row.
# Run from the repository root after `cargo build --release`.
set -euo pipefail
bin=target/release/clothlab
moving=$(mktemp --suffix .toml)
still=$(mktemp --suffix .toml)
sed 's/^self_collision = true/self_collision = false/' scenes/cloth-twist.toml > "$moving"
sed 's/^motion = .*$//' "$moving" > "$still"
for round in 1 2 3; do
  for n in 128 256; do
    for backend in cpu-par wgpu vulkan gl; do
      for which in moving still; do
        scene=$moving
        [ "$which" = still ] && scene=$still
        out=$($bin sim --scene "$scene" --backend "$backend" --n "$n" --steps 320 2>&1)
        sub=$(echo "$out" | awk '/^time\/substep/ {print $2}')
        frame=$(echo "$out" | awk '$1 == "frame" {print $2}')
        pins=$(echo "$out" | awk '$1 == "pins" {print $2}')
        echo "round $round n $n $backend $which substep_us $sub frame_us $frame pins_us ${pins:-0}"
      done
    done
  done
done
rm -f "$moving" "$still"
