#!/usr/bin/env bash
A=$1 B=$2 R=$3
for r in $(seq $R); do
 for c in "heap64|--scene scenes/thin-heap.toml --steps 800" "heap128|--scene scenes/thin-heap.toml --n 128 --steps 320" "twist|--scene scenes/twist-triangles.toml --integrator vbd --set substeps=10 --set vbd_iterations=4 --steps 600"; do
  name=${c%%|*} args=${c#*|}
  for be in cpu cpu-par; do for ab in A B; do bin=$A; [ $ab = B ] && bin=$B
   echo "$r $name $be $ab $($bin sim $args --backend $be | awk '/^wall time/{print $3}')"
  done; done
 done
done
