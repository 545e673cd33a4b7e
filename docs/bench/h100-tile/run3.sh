#!/bin/bash
# A device call for the tiled substep (run on an H200 on 2026-11-27: ../h200-tile): today's tiled substep
# (no workgroup zeroing on any API, dense stages, the last stage written straight out) and
# temporal blocking on a real GPU, which the call of 2026-11-25 did not reach.
# 1. validate fusion=tile (n = 37, one strain pass: partial tiles) and temporal=on on Vulkan,
#    wgpu and GL; 2. A = optimized, B = +fusion=tile, C = +fusion=tile +temporal=on,
#    interleaved per API and size, ROUNDS rounds, ns per particle-substep (sim's median of
#    GPU timestamps); every run's full output kept (per-kernel tables). Results under /tmp/r,
#    packed into $OUT/results.tgz after every size.
# Here, first: cargo build --release -p clothlab-app; mkdir -p .dev; cp target/release/clothlab
# .dev/; strip .dev/clothlab; gzip -9 .dev/clothlab (43 MB stripped, 16 MB gzipped: the tree
# and the carried paths travel within 64 MiB); the loaders into .gl (the device tool's README);
# then run(command="gunzip .dev/clothlab.gz && chmod +x .dev/clothlab && bash
# docs/bench/h100-tile/run3.sh", carry=[".dev", ".gl"], timeout_s=540)
# 341 s on the H200 of 2026-11-27.
# A dry run on lavapipe: LOCAL=1 B=target/release/clothlab OUT=/tmp/o SIZES="32 64" ROUNDS=1 bash …
set -u
if [ -z "${LOCAL:-}" ]; then
  # shellcheck source=../device-env.sh
  . docs/bench/device-env.sh
fi
SIZES=${SIZES:-"128 256 512 1024 2048"}
ROUNDS=${ROUNDS:-2}
R=/tmp/r; rm -rf $R; mkdir -p $R "$OUT"
pack() { tar czf "$OUT/results.tgz" -C /tmp r; }
nvidia-smi > $R/nvidia-smi.txt 2>&1
for b in vulkan wgpu gl; do
  for t in off on; do
    ( time timeout 90 "$B" validate --backends $b --set-variant fusion=tile --set-variant temporal=$t \
      --n 37 --steps 32 ) > $R/validate-$b-temporal-$t.txt 2>&1
  done
done
pack
for r in $(seq "$ROUNDS"); do
  for n in $SIZES; do
    for b in vulkan wgpu gl; do
      for v in A B C; do
        x=""
        [ $v = B ] && x="--set-variant fusion=tile"
        [ $v = C ] && x="--set-variant fusion=tile --set-variant temporal=on"
        # shellcheck disable=SC2086
        timeout 40 "$B" sim --backend $b --n $n --steps 320 $x > $R/sim-$r-$n-$b-$v.txt 2>&1
        t=$(grep -m1 "time/substep" $R/sim-$r-$n-$b-$v.txt | sed 's/.*median (//; s/ ns.*//')
        echo "$r $n $b $v ${t:-none}" >> $R/abc.txt
      done
    done
    pack
  done
done
pack
cat $R/abc.txt
