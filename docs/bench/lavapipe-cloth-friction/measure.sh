#!/bin/bash
# Friction between cloths: the settled heap at n = 128 (self_thickness 8 mm,
# 1600 substeps: it lands and folds onto itself) with self-collision, interleaved per
# round and backend: `old` — the binary before friction between cloths ($OLD, optional),
# `share` — this checkout without Coulomb's coefficients (the response's friction branch
# not taken), `coulomb` — with μs 0.5, μk 0.3 (friction at every contact between cloths,
# and at the floor). Prints one line per run: ms per substep (median), then the hash and
# the response (µs, median). Run from the repository root after `cargo build --release`.
old=${OLD:-}
for round in $(seq "${ROUNDS:-2}"); do
  for b in ${BACKENDS:-cpu-par wgpu vulkan gl}; do
    for v in ${old:+old} share coulomb; do
      bin=./target/release/clothlab
      [ "$v" = old ] && bin=$old
      mu=""
      [ "$v" = coulomb ] && mu="--set static_friction=0.5 --set kinetic_friction=0.3"
      # shellcheck disable=SC2086 # the extra arguments are words
      out=$(NODEVICE_SELECT=1 $bin sim --backend "$b" --scene scenes/heap.toml --n 128 --steps 1600 \
        --set self_thickness=0.008 $mu 2>&1)
      echo "r$round $b $v: $(echo "$out" | grep time/substep | awk '{print $2}') | $(echo "$out" | grep -E '^  self_(hash|collide)' | awk '{print $1"="$2}' | tr '\n' ' ')"
    done
  done
done
