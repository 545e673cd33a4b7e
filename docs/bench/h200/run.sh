#!/bin/bash
# The device run of 2026-11-26: validate the irregular meshes, and the
# mesh-vs-grid bench with a 250k and a 1M Delaunay disc. Results under /tmp/r, packed
# into $OUT/results.tgz after every step.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
export NODEVICE_SELECT=1
B=$PWD/.dev/clothlab
R=/tmp/r; mkdir -p $R
pack() { tar czf $OUT/results.tgz -C /tmp r; }
nvidia-smi > $R/nvidia-smi.txt 2>&1
nproc >> $R/nvidia-smi.txt
PY=/opt/torch/.venv/bin/python3; [ -x $PY ] || PY=python3
$PY scenes/meshes/make_irregular.py --big 250000 /tmp/disc250k.obj > $R/meshes.txt 2>&1 &
$PY scenes/meshes/make_irregular.py --big 1000000 /tmp/disc1m.obj >> $R/meshes.txt 2>&1 &
for s in mesh-fan mesh-cape; do
  ( time timeout 75 $B validate --scene scenes/$s.toml ) > $R/validate-$s.txt 2>&1
done
( time timeout 75 $B validate --scene scenes/mesh-cape.toml --integrator xpbd ) > $R/validate-mesh-cape-xpbd.txt 2>&1
wait; pack
M="NVIDIA H200, 16 cores (device run, 2026-11-26)"
( time timeout 200 $B bench --mesh-vs-grid --sizes 501 --irregular /tmp/disc250k.obj \
  --backends cpu-par,wgpu-naive,wgpu,vulkan-naive,vulkan,gl-naive,gl --iters 320 --repeat 3 \
  --machine "$M" --out $R/mesh-vs-grid-250k ) > $R/mvg-250k.txt 2>&1
pack
( time timeout 120 $B bench --mesh-vs-grid --sizes 1000 --irregular /tmp/disc1m.obj \
  --backends wgpu,vulkan,gl --iters 320 --repeat 3 --machine "$M" --out $R/mesh-vs-grid-1m ) > $R/mvg-1m.txt 2>&1
pack
ls -R $R
