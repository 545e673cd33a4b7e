#!/bin/bash
# Interleaved A/B: self-collision on vs off, per backend and size; prints the sim lines.
cd /work/main
out=/tmp/measure
mkdir -p $out
for round in 1 2; do
 for n in 128 512; do
  if [ $n = 128 ]; then t=0.008; steps=1600; else t=0.002; steps=160; fi
  for b in cpu cpu-par wgpu vulkan; do
   for sc in true false; do
    f=$out/$b-$n-$sc-$round.txt
    NODEVICE_SELECT=1 ./target/release/clothlab sim --backend $b --scene scenes/heap.toml --n $n --steps $steps --set self_collision=$sc --set self_thickness=$t > $f 2>&1
    echo "$b n=$n sc=$sc r=$round: $(grep time/substep $f) | $(grep -E '^  self_(hash|collide)' $f | awk '{print $1"="$2}' | tr '\n' ' ')"
   done
  done
 done
done
