#!/usr/bin/env bash
# Per kernel on single-threaded lavapipe/llvmpipe (LP_NUM_THREADS=0: one thread, the
# steadiest timing on this VM): `bench --backends $BACKENDS --sizes $SIZES --iters 96` of
# 7015e92, of the pass counting inline and of the pass down strips, interleaved, ROUNDS
# rounds (FIRST: the first round's number, to add rounds to a run); each run's report.md lands in $OUT/<which>_<round>/, and kernels.py tabulates.
# Usage: A7015=… NEW=… OUT=/tmp/kb ROUNDS=3 kernels.sh; python3 kernels.py /tmp/kb > kernels.md
set -uo pipefail
: "${A7015:?}" "${NEW:?}" "${OUT:?}"
ROUNDS=${ROUNDS:-3}
BACKENDS=${BACKENDS:-vulkan,wgpu,gl}
SIZES=${SIZES:-256,512}
for r in $(seq "${FIRST:-1}" "$ROUNDS"); do
  for which in A7015 INLINE STRIP; do
    case $which in
      A7015) bin=$A7015; x="" ;;
      INLINE) bin=$NEW; x="--set-variant strain_counts=inline" ;;
      STRIP) bin=$NEW; x="--set-variant strain_counts=strip" ;;
    esac
    # shellcheck disable=SC2086
    LP_NUM_THREADS=0 "$bin" bench --backends "$BACKENDS" --sizes "$SIZES" --iters 96 $x --out "$OUT/${which}_$r" >/dev/null 2>&1
  done
done
