#!/usr/bin/env bash
# Two scenes A and B interleaved (A B A B …) per round, grid size and backend: `sim`'s
# median time per substep (kernel timestamps on the GPU APIs), its frame median, and the
# median of each kernel row named in ROWS. Shared by the A/B benchmarks under docs/bench
# (lavapipe-pins, lavapipe-bodies). Run from the repository root after
# `cargo build --release`:
#   docs/bench/ab-scenes.sh A.toml B.toml LABEL_A LABEL_B "128 256" "cpu-par wgpu vulkan gl" ROUNDS "row1 row2"
# A_ARGS and B_ARGS (optional) are added to A's and B's `sim` command: one scene under two
# variants (lavapipe-sdf-image: `B_ARGS="--set-variant sdf=image"`).
set -euo pipefail
bin=${CLOTHLAB:-target/release/clothlab}
a=$1 b=$2 label_a=$3 label_b=$4 sizes=$5 backends=$6 rounds=$7 rows=${8:-}
steps=${STEPS:-320}
for round in $(seq 1 "$rounds"); do
  for n in $sizes; do
    for backend in $backends; do
      for which in "$label_a" "$label_b"; do
        scene=$a extra=${A_ARGS:-}
        [ "$which" = "$label_b" ] && scene=$b extra=${B_ARGS:-}
        # shellcheck disable=SC2086 # the extra arguments are words
        out=$($bin sim --scene "$scene" --backend "$backend" --n "$n" --steps "$steps" $extra 2>&1)
        sub=$(echo "$out" | awk '/^time\/substep/ {print $2}')
        frame=$(echo "$out" | awk '$1 == "frame" {print $2}')
        line="round $round n $n $backend $which substep_us $sub frame_us $frame"
        for row in $rows; do
          # A row's label is its words before the first number, joined by '_'
          # (`cpu record` is cpu_record; integrate+collide stays one word).
          v=$(echo "$out" | awk -v r="$row" '{
            k = 1; label = "";
            while (k <= NF && $k !~ /^[0-9.]+$/) { label = label (k > 1 ? "_" : "") $k; k++ }
            if (label == r && k <= NF) { print $k; exit }
          }')
          line="$line ${row}_us ${v:-0}"
        done
        echo "$line"
      done
    done
  done
done
