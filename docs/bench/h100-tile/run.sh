#!/bin/bash
# The device run of 2026-11-25: the tiled substep (fusion=tile) on the H100.
# 1. validate the tile recipe against the CPU on Vulkan, wgpu and GL (n = 37, two strain
#    passes: partial tiles at the far edges); 2. the optimized preset (A) against
#    optimized+fusion=tile (B), interleaved A B per API and size, two rounds, ns per
#    particle-substep from GPU timestamps (sim's median). Results under /tmp/r, packed into
#    $OUT/results.tgz after every step.
set -u
# shellcheck source=../device-env.sh
. docs/bench/device-env.sh
R=/tmp/r; mkdir -p $R
pack() { tar czf $OUT/results.tgz -C /tmp r; }
nvidia-smi > $R/nvidia-smi.txt 2>&1
( time timeout 100 $B validate --backends vulkan,wgpu,gl --set-variant fusion=tile --n 37 --steps 64 \
  --set strain_iterations=2 ) > $R/validate-tile.txt 2>&1
pack
for r in 1 2; do
  for n in 128 256 512 1024 2048; do
    for b in vulkan wgpu gl; do
      for v in A B; do
        x=""; [ $v = B ] && x="--set-variant fusion=tile"
        # shellcheck disable=SC2086
        timeout 40 $B sim --backend $b --n $n --steps 320 $x > $R/sim-$r-$n-$b-$v.txt 2>&1
        t=$(grep -m1 "time/substep" $R/sim-$r-$n-$b-$v.txt | sed 's/.*median (//; s/ ns.*//')
        echo "$r $n $b $v $t" >> $R/ab.txt
      done
    done
    pack
  done
done
pack
cat $R/ab.txt
