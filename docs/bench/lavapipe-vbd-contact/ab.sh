#!/bin/bash
# VBD on the thin heap: the contact after the sweeps (d826011) against inside the solves
# (this change), interleaved, 3 rounds. LP_NUM_THREADS=0.
export LP_NUM_THREADS=0
# A: the binary of d826011 (the contact after the sweeps), B: of 5987aa3 (inside the solves).
A=${A:?release binary of d826011}; B=${B:?release binary of 5987aa3}
S=$(dirname "$0")/../../../scenes/thin-heap.toml
for round in 1 2 3; do
  for case in "vulkan 24 1440" "cpu-par 32 1600"; do
    set -- $case
    for bin in $A $B; do
      out=$(xvfb-run -a $bin sim --scene $S --integrator vbd --backend $1 --n $2 --steps $3 --check-crossings 2>&1)
      t=$(echo "$out" | grep "time/substep" | awk '{print $2}')
      vbd=$(echo "$out" | grep "^  vbd " | awk '{print $2}')
      cr=$(echo "$out" | grep "every frame" | cut -c16-)
      pairs=$(echo "$out" | grep "contact pairs" | awk '{print $3, $10}')
      last=$(echo "$out" | grep "last substep" | cut -c17-)
      echo -e "$round\t$(basename $bin)\t$1\t$2\t$t\t$vbd\t$cr\t$pairs\t$last"
    done
  done
done
