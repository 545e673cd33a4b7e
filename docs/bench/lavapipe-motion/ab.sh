#!/usr/bin/env bash
# The cost of motion: the spinning-sphere scene with its sphere spinning (A)
# and still (B), interleaved A B A B, per backend and grid size (docs/bench/ab-scenes.sh):
# `sim`'s median time per substep (kernel timestamps on the GPU APIs), its frame median
# and the host's recording time per frame (`cpu record`).
# Run from the repository root after `cargo build --release`.
set -euo pipefail
still=$(mktemp --suffix .toml)
sed 's/^motion = .*$//' scenes/spinning-sphere.toml > "$still"
docs/bench/ab-scenes.sh scenes/spinning-sphere.toml "$still" moving still "128 256" "cpu-par wgpu vulkan gl" 3 cpu_record
rm -f "$still"
