#!/bin/bash
# The second device run of 2026-11-26: several cloths and the 1M-vertex disc.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
export NODEVICE_SELECT=1
B=$PWD/.dev/clothlab
R=/tmp/r; mkdir -p $R
pack() { tar czf $OUT/results.tgz -C /tmp r; }
PY=/opt/torch/.venv/bin/python3; [ -x $PY ] || PY=python3
$PY scenes/meshes/make_irregular.py --big 1000000 /tmp/disc1m.obj > $R/meshes.txt 2>&1 &
( time timeout 90 $B validate --scene scenes/two-cloths.toml ) > $R/validate-two-cloths.txt 2>&1
( time timeout 60 $B sim --backend vulkan --scene scenes/two-cloths.toml --steps 2400 --out /tmp/two.json ) > $R/sim-two-cloths-vulkan.txt 2>&1
wait; pack
M="NVIDIA H200, 16 cores (device run, 2026-11-26)"
( time timeout 330 $B bench --mesh-vs-grid --sizes 1000 --irregular /tmp/disc1m.obj \
  --backends wgpu,vulkan,gl --iters 320 --repeat 2 --machine "$M" --out $R/mesh-vs-grid-1m ) > $R/mvg-1m.txt 2>&1
pack
ls -R $R
