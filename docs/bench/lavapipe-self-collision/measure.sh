#!/bin/bash
# Interleaved: per backend and size, self-collision on and off with this checkout's
# release binary, and on with an older binary ($OLD, optional: the before of a change),
# round after round. Prints one line per run: ms per substep (median), the hash and the
# response (µs, median). Run from the repository root after `cargo build --release`.
old=${OLD:-}
for round in $(seq ${ROUNDS:-2}); do
 for n in 128 512; do
  if [ $n = 128 ]; then t=0.008; steps=1600; else t=0.002; steps=160; fi
  for b in cpu cpu-par wgpu vulkan; do
   for v in ${old:+old-on} on off; do
    bin=./target/release/clothlab; [ $v = old-on ] && bin=$old
    sc=true; [ $v = off ] && sc=false
    out=$(NODEVICE_SELECT=1 $bin sim --backend $b --scene scenes/heap.toml --n $n --steps $steps --set self_collision=$sc --set self_thickness=$t 2>&1)
    echo "r$round n=$n $b $v: $(echo "$out" | grep time/substep | awk '{print $2}') | $(echo "$out" | grep -E '^  self_(hash|collide)' | awk '{print $1"="$2}' | tr '\n' ' ')"
   done
  done
 done
done
