#!/bin/bash
# A device call for the wave's last GPU measurements, on a lent NVIDIA GPU, one call:
# 1. validate the strain pass down strips (strain_counts=strip) against the CPU twins on
#    Vulkan, wgpu and GL (n = 37: partial strips and blocks);
# 2. the default scene, the optimized preset as a GPU fits it (the pass counting inline)
#    against the same with --set-variant strain_counts=strip, interleaved per API and size,
#    ROUNDS rounds, `sim --steps 160`: whether the strips, the preset's on a CPU adapter,
#    would pay on a GPU;
# 3. the contact between triangles: the 50 x 50 twist (scenes/twist-triangles.toml) at 10
#    substeps a frame on every API (issue: under 1 ms a frame on Vulkan; Newton reports 8 ms
#    on an RTX 5090), with the crossings counted; a stack of 20 sheets of 64 x 64
#    (stack20.py) on every API; and 60 sheets (245 760 vertices, OGC's 246 K) on Vulkan; the
#    stacks' crossings counted in their final state (sim's own line), the twist's every frame.
# Every run's full output kept (per-kernel tables, frame medians); results under /tmp/r,
# packed into $OUT/results.tgz after each part.
# Here, first: cargo build --release -p clothlab-app; mkdir -p .dev; cp target/release/clothlab
# .dev/; strip .dev/clothlab; gzip -9 .dev/clothlab; the loaders into .gl (the device tool's
# README); then run(command="gunzip .dev/clothlab.gz && chmod +x .dev/clothlab && bash
# docs/bench/device-wave5/run.sh", carry=[".dev", ".gl"], timeout_s=540)
# A dry run on lavapipe: LOCAL=1 B=target/release/clothlab OUT=/tmp/o SIZES="32" ROUNDS=1 \
#   STEPS=16 TWIST_STEPS=20 STACK="2 8" BIG="3 8" bash docs/bench/device-wave5/run.sh
set -u
here=$(cd "$(dirname "$0")" && pwd)
if [ -z "${LOCAL:-}" ]; then
  # shellcheck source=../device-env.sh
  . docs/bench/device-env.sh
fi
SIZES=${SIZES:-"256 1024 2048"}
ROUNDS=${ROUNDS:-2}
STEPS=${STEPS:-160}
TWIST_STEPS=${TWIST_STEPS:-600}
read -r STACK_SHEETS STACK_N <<< "${STACK:-20 64}"
read -r BIG_SHEETS BIG_N <<< "${BIG:-60 64}"
R=/tmp/r; rm -rf $R; mkdir -p $R "$OUT"
pack() { tar czf "$OUT/results.tgz" -C /tmp r; }
nvidia-smi > $R/nvidia-smi.txt 2>&1
for b in vulkan wgpu gl; do
  ( time timeout 60 "$B" validate --backends $b --set-variant strain_counts=strip --n 37 --steps 32 ) \
    > $R/validate-strip-$b.txt 2>&1
done
pack
for r in $(seq "$ROUNDS"); do
  for n in $SIZES; do
    for b in vulkan wgpu gl; do
      for v in FIT STRIP; do
        x=""
        [ $v = STRIP ] && x="--set-variant strain_counts=strip"
        # shellcheck disable=SC2086
        timeout 40 "$B" sim --backend $b --n "$n" --steps "$STEPS" $x > $R/sim-$r-$n-$b-$v.txt 2>&1
        t=$(grep -m1 "time/substep" $R/sim-$r-$n-$b-$v.txt | sed 's/.*median (//; s/ ns.*//')
        echo "$r $n $b $v ${t:-none}" >> $R/runs.txt
      done
    done
  done
  pack
done
for b in vulkan wgpu gl; do
  timeout 90 "$B" sim --scene scenes/twist-triangles.toml --backend $b --set substeps=10 \
    --steps "$TWIST_STEPS" --check-crossings > $R/twist-$b.txt 2>&1
done
pack
python3 "$here/stack20.py" "$STACK_SHEETS" "$STACK_N" > $R/stack-small.toml
python3 "$here/stack20.py" "$BIG_SHEETS" "$BIG_N" > $R/stack-big.toml
for b in vulkan wgpu gl; do
  timeout 120 "$B" sim --scene $R/stack-small.toml --backend $b --steps "$STEPS" \
    > $R/stack-small-$b.txt 2>&1
done
pack
timeout 150 "$B" sim --scene $R/stack-big.toml --backend vulkan --steps "$STEPS" > $R/stack-big-vulkan.txt 2>&1
pack
cat $R/runs.txt
grep -H -E "^(time/substep|crossings|grid|substeps)|^  frame" $R/twist-*.txt $R/stack-*.txt
