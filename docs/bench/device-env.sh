#!/bin/bash
# Sourced by the device runs' scripts (docs/bench/*/run*.sh) on a lent NVIDIA machine: unpack
# the carried loader packages (.gl, see the device tool's README), point Vulkan and EGL at
# NVIDIA's drivers, skip Mesa's device-select layer, and name the carried binary $B.
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
export NODEVICE_SELECT=1
B=$PWD/.dev/clothlab
export B
