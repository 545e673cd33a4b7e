#!/usr/bin/env bash
# The cost of moving pins: the cloth-twist scene without self-collision, its
# two pinned strips turning (A) and held still (B: the same [[pins]] without a motion),
# interleaved A B A B, per backend and grid size (docs/bench/ab-scenes.sh): `sim`'s
# median time per substep (kernel timestamps on the GPU APIs), its frame median and the
# `pins` kernel's row. Run from the repository root after `cargo build --release`.
set -euo pipefail
moving=$(mktemp --suffix .toml)
still=$(mktemp --suffix .toml)
sed 's/^self_collision = true/self_collision = false/' scenes/cloth-twist.toml > "$moving"
sed 's/^motion = .*$//' "$moving" > "$still"
docs/bench/ab-scenes.sh "$moving" "$still" moving still "128 256" "cpu-par wgpu vulkan gl" 3 pins
rm -f "$moving" "$still"
