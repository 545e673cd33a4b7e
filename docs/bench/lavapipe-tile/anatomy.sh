#!/usr/bin/env bash
# Where the tiled substep's time goes on lavapipe / llvmpipe (2026-11-27): three
# builds of the release binary that differ only in shaders/wgsl/substep_tile.wgsl —
#   base:      the kernel as committed (256 invocations a workgroup, 4 region points each);
#   w32:       32 invocations a workgroup, 32 points each (same arithmetic, same bits);
#   nobarrier: every workgroupBarrier() commented out (WRONG results: timing only, to
#              see what the barriers cost);
# then A/B/... interleaved rounds of `sim --steps 32`, ns per particle-substep (the median
# of the GPU timestamps), with and without the strain pass. Run from the repository root;
# builds into target/release and copies each binary to $DIR. The kernel as it was (with
# any edits of yours) is put back and target/release rebuilt from it on exit, also when
# stopped: no wrong-results binary is left behind.
set -u
DIR=${DIR:-/tmp/tile-anatomy}
ROUNDS=${ROUNDS:-3}
mkdir -p "$DIR"
K=shaders/wgsl/substep_tile.wgsl
cp "$K" "$DIR/kernel.orig"
restore() { cp "$DIR/kernel.orig" "$K"; }
build() { cargo build --release -q -p clothlab-app && cp target/release/clothlab "$DIR/$1"; restore; }
if [ ! -x "$DIR/nobarrier" ]; then
  trap 'restore; cargo build --release -q -p clothlab-app' EXIT
  build base
  sed -i 's/const TILE_THREADS: u32 = 256u;/const TILE_THREADS: u32 = 32u;/; s/const PER_THREAD: u32 = 4u;/const PER_THREAD: u32 = 32u;/; s/@workgroup_size(256)/@workgroup_size(32)/' "$K"
  build w32
  sed -i 's/^\(\s*\)workgroupBarrier();/\1\/\/ workgroupBarrier();/' "$K"
  build nobarrier
fi
t() { "$DIR/$1" sim --backend "$2" --n "$3" --steps 32 "${@:4}" 2>&1 | grep -m1 "time/substep" | sed 's/.*median (//; s/ ns.*//'; }
for r in $(seq "$ROUNDS"); do
  for b in vulkan gl; do
    for n in 256 512; do
      for s in 1 0; do
        o=$(t base $b $n --set strain_iterations=$s)
        tb=$(t base $b $n --set strain_iterations=$s --set-variant fusion=tile)
        tw=$(t w32 $b $n --set strain_iterations=$s --set-variant fusion=tile)
        tn=$(t nobarrier $b $n --set strain_iterations=$s --set-variant fusion=tile)
        o2=$(t base $b $n --set strain_iterations=$s)
        echo "round $r $b n=$n passes=$s optimized $o tile $tb tile-w32 $tw tile-nobarrier $tn optimized-again $o2"
      done
    done
  done
done
