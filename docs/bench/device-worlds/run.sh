#!/bin/bash
# A device call for the worlds (a batch of worlds, every kernel dispatched once for all),
# on a lent NVIDIA GPU, one call:
# 1. validate --envs 4 on Vulkan, wgpu and GL: each world of a batch against its single run
#    on the same API (bound 0), the default scene at n = 32 with the damping and the wind
#    differing (the check that the `_w` kernels keep worlds apart on a real GPU);
# 2. bench --envs: a 3.5 K-particle cloth (n = 59, 3 481 particles, the size of Newton's
#    shirt) at 8 … 8 192 worlds on each API, the batch against the same worlds as separate
#    simulations (at most 64), world-substeps per second (Newton publishes 1.7 ms per
#    world-step of its 3.5 K-particle shirt, 8 worlds in 31 ms on an RTX PRO 6000); a batch
#    past an API's largest binding is refused with the most worlds that fit (in the notes);
# 3. the same at n = 16 and 32 (the sizes measured on lavapipe: docs/benchmarking.md).
# 4. validate --envs 4 with each contact on Vulkan (the thin heap at n = 32: triangles;
#    the heap: particles), and bench --envs 1,64,1024 at n = 32 with the contact between
#    triangles on vulkan (its search every substep is what a batch does not share).
# Results under /tmp/r, packed into $OUT/results.tgz after each part.
# Here, first: cargo build --release -p clothlab-app; mkdir -p .dev; cp target/release/clothlab
# .dev/; strip .dev/clothlab; gzip -9 .dev/clothlab; the loaders into .gl (the device tool's
# README); then run(command="gunzip .dev/clothlab.gz && chmod +x .dev/clothlab && bash
# docs/bench/device-worlds/run.sh", carry=[".dev", ".gl"], timeout_s=540)
# A dry run on lavapipe: LOCAL=1 B=target/release/clothlab OUT=/tmp/o BIG="8,64" SMALL="1,16" \
#   ROUNDS=1 bash docs/bench/device-worlds/run.sh
set -u
if [ -z "${LOCAL:-}" ]; then
  # shellcheck source=../device-env.sh
  . docs/bench/device-env.sh
fi
BIG=${BIG:-"8,64,512,1024,4096,8192"}
SMALL=${SMALL:-"1,16,256,1024,4096"}
ROUNDS=${ROUNDS:-2}
R=/tmp/r; rm -rf $R; mkdir -p $R "$OUT"
pack() { tar czf "$OUT/results.tgz" -C /tmp r; }
nvidia-smi > $R/nvidia-smi.txt 2>&1
for b in vulkan wgpu gl; do
  ( time timeout 60 "$B" validate --envs 4 --backends $b --n 32 --steps 64 \
      --set 'damping=[0,0.002,0.004,0.008]' --set 'wind=[[0,0,0],[2,0,0],[0,0,3],[4,0,1]]' ) \
    > $R/validate-envs-$b.txt 2>&1
done
pack
( time timeout 240 "$B" bench --envs "$BIG" --sizes 59 --backends wgpu,vulkan,gl --iters 4 \
    --repeat "$ROUNDS" --machine "$(nvidia-smi --query-gpu=name --format=csv,noheader | head -1)" \
    --out $R/big ) > $R/bench-big.txt 2>&1
pack
( time timeout 150 "$B" bench --envs "$SMALL" --sizes 16,32 --backends wgpu,vulkan,gl --iters 4 \
    --repeat "$ROUNDS" --out $R/small ) > $R/bench-small.txt 2>&1
pack
for scene in thin-heap heap; do
  ( time timeout 30 "$B" validate --envs 4 --backends vulkan --scene scenes/$scene.toml --n 32 --steps 64 \
      --set 'damping=[0,0.002,0.004,0.008]' ) > $R/validate-envs-$scene.txt 2>&1
done
( time timeout 60 "$B" bench --envs 1,64,1024 --sizes 32 --backends vulkan --iters 4 \
    --set 'self_collision="triangles"' --set self_thickness=0.004 --out $R/contact ) > $R/bench-contact.txt 2>&1
pack
