#!/usr/bin/env bash
# clothlab against Taichi's cloth example (taichi_cloth.py), interleaved, ROUNDS rounds, at
# n = N (512): lavapipe (clothlab --backend vulkan, Taichi arch=vulkan; lavapipe's own
# thread count for both) and the CPU on 2 threads (clothlab cpu-par on the 2-core machine,
# Taichi arch=cpu with cpu_max_num_threads=2), for each clothlab binary in BINS
# ("NAME=PATH ..."). Prints ns per particle-substep.
#   BINS="today=target/release/clothlab" ROUNDS=3 docs/bench/lavapipe-taichi/run.sh
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
N=${N:-512}
ns() { sed -n 's/.*(\([0-9.]*\) ns per particle-substep).*/\1/p'; }
for r in $(seq 1 "${ROUNDS:-3}"); do
  for nb in ${BINS:-today=$here/../../../target/release/clothlab}; do
    echo "round $r vulkan-$N ${nb%%=*} $("${nb#*=}" sim --backend vulkan --n "$N" --steps 24 2>/dev/null | ns)"
  done
  echo "round $r vulkan-$N taichi $(python3 "$here/taichi_cloth.py" vulkan "$N" 8 2>/dev/null | awk '/^taichi / {print $6}')"
  for nb in ${BINS:-today=$here/../../../target/release/clothlab}; do
    echo "round $r cpu2-$N ${nb%%=*} $("${nb#*=}" sim --backend cpu-par --n "$N" --steps 160 2>/dev/null | ns)"
  done
  echo "round $r cpu2-$N taichi $(TI_THREADS=2 python3 "$here/taichi_cloth.py" cpu "$N" 40 2>/dev/null | awk '/^taichi / {print $6}')"
done
