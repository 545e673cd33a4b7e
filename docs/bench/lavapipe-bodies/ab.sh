#!/usr/bin/env bash
# What a body costs: the spinning-sphere scene with its sphere a body made of
# triangles (A: scenes/body-sphere.toml, the icosphere's field of 48 cells across, 8
# loads and a trilinear sample per particle inside its grid) against the analytic sphere
# (B: scenes/spinning-sphere.toml), interleaved A B A B per backend and grid size
# (docs/bench/ab-scenes.sh): the time per substep, the frame, and the kernel that
# collides (`integrate+collide` on the GPU APIs' optimized recipe).
# Run from the repository root after `cargo build --release`.
set -euo pipefail
docs/bench/ab-scenes.sh scenes/body-sphere.toml scenes/spinning-sphere.toml body sphere "128 256" "cpu-par wgpu vulkan gl" 3 integrate+collide
