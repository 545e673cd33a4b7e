#!/bin/bash
# A device call for "Pay only for what the scene uses" on a lent NVIDIA GPU: the default scene
# before the wave that added rods, bodies, Coulomb friction and moving colliders (OLD: the
# stripped release binary of 7015e92) against today's (NEW: the optimized preset, the kernels
# compiled for the scene and the strain pass counting for itself), today's with the count
# dispatch (NEWDISP: --set-variant strain_counts=dispatch) and today's unspecialised
# (NEWOFF: --set-variant specialize=off), interleaved per API and size, ROUNDS rounds;
# `sim --steps 160` (10 frames of 16 substeps), ns per particle-substep as sim prints it
# (the median of the GPU timestamps); every run's full output kept (per-kernel tables).
# First: validate the new kernels (strain_counts=inline, dispatch) against the CPU twins on
# Vulkan, wgpu and GL. Results under /tmp/r, packed into $OUT/results.tgz after every size.
# Here, first: build both binaries (7015e92 in a worktree), strip and gzip them into .dev as
# old.gz and clothlab.gz; the loaders into .gl (the device tool's README); then
# run(command="gunzip .dev/*.gz && chmod +x .dev/* && bash docs/bench/h200-specialise/run.sh",
#     carry=[".dev", ".gl"], timeout_s=540)
# A dry run on lavapipe: LOCAL=1 B=target/release/clothlab OLD=/path/old OUT=/tmp/o SIZES="32" ROUNDS=1 bash …
set -u
if [ -z "${LOCAL:-}" ]; then
  # shellcheck source=../device-env.sh
  . docs/bench/device-env.sh
  OLD=$PWD/.dev/old
fi
SIZES=${SIZES:-"256 512 1024 2048"}
ROUNDS=${ROUNDS:-2}
R=/tmp/r; rm -rf $R; mkdir -p $R "$OUT"
pack() { tar czf "$OUT/results.tgz" -C /tmp r; }
nvidia-smi > $R/nvidia-smi.txt 2>&1
for b in vulkan wgpu gl; do
  for s in inline dispatch; do
    ( time timeout 60 "$B" validate --backends $b --set-variant strain_counts=$s --n 37 --steps 32 ) \
      > $R/validate-$b-$s.txt 2>&1
  done
done
# With self-collision (the last pass fused with the hash's count), on a grid and on a mesh
# (an irregular table: the pass's rows).
( time timeout 90 "$B" validate --backends vulkan,gl --scene scenes/heap.toml --n 24 --steps 16 ) \
  > $R/validate-heap.txt 2>&1
( time timeout 90 "$B" validate --backends vulkan,gl --scene scenes/mesh-heap.toml --steps 16 ) \
  > $R/validate-mesh-heap.txt 2>&1
pack
for r in $(seq "$ROUNDS"); do
  for n in $SIZES; do
    for b in vulkan wgpu gl; do
      for v in OLD NEW NEWDISP NEWOFF; do
        bin=$B; x=""
        [ $v = OLD ] && bin=$OLD
        [ $v = NEWDISP ] && x="--set-variant strain_counts=dispatch"
        [ $v = NEWOFF ] && x="--set-variant specialize=off"
        # shellcheck disable=SC2086
        timeout 40 "$bin" sim --backend $b --n $n --steps 160 $x > $R/sim-$r-$n-$b-$v.txt 2>&1
        t=$(grep -m1 "time/substep" $R/sim-$r-$n-$b-$v.txt | sed 's/.*median (//; s/ ns.*//')
        echo "$r $n $b $v ${t:-none}" >> $R/runs.txt
      done
    done
    pack
  done
done
pack
cat $R/runs.txt
