#!/bin/sh
# Prepares a bare Linux machine with an NVIDIA GPU and its driver mounted (no network)
# and runs tools/gpu_frames.py there: OUT [--base DIR] [--rounds N] go through.
# It needs beside the checkout, fetched on a machine with a network:
#   .gl/   the GL loaders as Debian packages (libegl1 libglvnd0 libopengl0 libgl1 libglx0
#          libgles2 ocl-icd-libopencl1: `apt-get download ...`), unpacked into / here;
#   .whl/  the venv's wheels for the machine's Python (`pip download --no-deps
#          --python-version 3.12 ...` of numpy<2, moderngl, glcontext, zstandard, lz4,
#          pyopencl, pytools, platformdirs, siphash24), installed into /tmp/site;
#   .base/ the revision to compare with (`git archive REV voxel_addon gpu shaders`).
set -e
out=$1; shift
for f in .gl/*.deb; do dpkg -x "$f" /; done
nv=/usr/local/nvidia
for d in $nv/lib64 $nv/lib; do [ -d $d ] && echo $d >> /etc/ld.so.conf.d/nvidia-mount.conf; done
ldconfig
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
    --target /tmp/site .whl/*.whl
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 XDG_CACHE_HOME=/tmp/cache
# the driver's EGL vendor file and OpenCL library, where its mount has them
egl=$(ls $nv/share/glvnd/egl_vendor.d/*nvidia*.json /usr/share/glvnd/egl_vendor.d/*nvidia*.json 2>/dev/null | head -1)
[ -n "$egl" ] && export __EGL_VENDOR_LIBRARY_FILENAMES=$egl
cl=$(ls $nv/lib64/libnvidia-opencl.so.1 $nv/lib/libnvidia-opencl.so.1 \
     /usr/lib/x86_64-linux-gnu/libnvidia-opencl.so.1 2>/dev/null | head -1)
mkdir -p /tmp/icd && [ -n "$cl" ] && echo "$cl" > /tmp/icd/nvidia.icd
export OCL_ICD_VENDORS=/tmp/icd
nvidia-smi -L || true
echo "egl: $egl  opencl: $cl"
python3 - <<'PY'
import pyopencl as cl
for p in cl.get_platforms():
    print("OpenCL:", p.name, p.version, [d.name for d in p.get_devices()])
PY
python3 tools/gpu_frames.py "$out" "$@"
