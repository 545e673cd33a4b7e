#!/usr/bin/env bash
# XPBD in small steps: the default scene draped for 100 frames (1.67 s) with
# physical stiffness, one XPBD iteration per substep at 16 … 128 substeps per frame, against
# the many-iterations settings the 75-substep limit forced before; cpu-par. Prints the max
# structural strain, the lowest point and the time per substep (cost per simulated second =
# substeps per second of simulation × time per substep).
# Usage: BIN=path/to/clothlab xpbd_small_steps.sh "N:SUBSTEPS:ITERATIONS:STRAIN_PASSES" …
set -euo pipefail
: "${BIN:?the clothlab binary}"
for cfg in "$@"; do
  IFS=: read -r n sub it sp <<< "$cfg"
  out=$("$BIN" sim --backend cpu-par --n "$n" --integrator xpbd --steps $((100 * sub)) \
    --set stiffness_units=physical --set substeps="$sub" --set xpbd_iterations="$it" \
    --set strain_iterations="$sp" 2>/dev/null)
  us=$(awk '/^time\/substep/ {print $2}' <<< "$out")
  strain=$(awk '/^max strain/ {print $3}' <<< "$out")
  low=$(awk '/^lowest point/ {print $3}' <<< "$out")
  cost=$(awk -v us="$us" -v s="$sub" 'BEGIN {printf "%.1f", us * 1e-6 * s * 60}')
  echo "n=$n substeps=$sub iterations=$it strain_passes=$sp max_strain=$strain lowest=$low us_per_substep=$us s_per_sim_s=$cost"
done
