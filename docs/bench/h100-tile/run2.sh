#!/bin/bash
# The second device call of 2026-11-25: the tile's kernel check on Vulkan with 0 and 1
# strain passes (the first call's 2 passes missed the kernel bound: compounding or a bug?),
# then GL (the first call's GL runs never finished within 40 s).
set -u
# shellcheck source=../device-env.sh
. docs/bench/device-env.sh
for s in 0 1; do
  ( time timeout 45 $B validate --backends vulkan --set-variant fusion=tile --n 37 --steps 16 \
    --set strain_iterations=$s ) > $OUT/validate-tile-vulkan-s$s.txt 2>&1
done
( time timeout 110 $B validate --backends gl --set-variant fusion=tile --n 37 --steps 16 ) > $OUT/validate-tile-gl-s1.txt 2>&1
