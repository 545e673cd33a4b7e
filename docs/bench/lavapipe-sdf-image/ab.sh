#!/usr/bin/env bash
# The bodies' distance fields in storage against the 3-D image(`sdf=image`):
# scenes/body-sphere.toml (the icosphere's field, 48 cells across) on each GPU API's
# optimized recipe, A = sdf=storage (8 loads and the kernel's trilinear arithmetic per
# particle in the grid), B = sdf=image (the texture unit interpolates: 1 filtered sample
# for φ, 6 more for the normal near the surface), interleaved A B A B per API and grid size
# (docs/bench/ab-scenes.sh): the time per substep, the frame, and `integrate+collide`.
# Run from the repository root after `cargo build --release`.
set -euo pipefail
B_ARGS="--set-variant sdf=image" docs/bench/ab-scenes.sh scenes/body-sphere.toml scenes/body-sphere.toml \
  storage image "128 256" "wgpu vulkan gl" 2 integrate+collide
