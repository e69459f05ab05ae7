#!/usr/bin/env bash
# Issue 48 on the GPU machine, after the set-up runs (../shared/device/README.md): what the work
# model (bench/work_model.py, on the CPU) is checked against. The armadillo at 100,000 spheres on
# Warp (cuda:0), fast mode, seed 0: every launch timed on the device (bench/profile_kernels.py),
# and three unprofiled runs.
#   source .gpu2/setup.sh && bash bench/gpu_issue48.sh            the armadillo of 100k triangles
#   source .gpu2/setup.sh && bash bench/gpu_issue48.sh small      the checkout's 20k-triangle armadillo:
#                                                                  the model's test (bench/work_model.py --constants)
set -uo pipefail
source bench/gpu_header.sh
[ -f /tmp/armadillo.obj ] || xz -dc .gpu2/armadillo.obj.xz > /tmp/armadillo.obj
export NDPACK_CACHE=/tmp/ndpack-gpu-cache WARP_CACHE_PATH=/tmp/ndpack-gpu-cache/warp
if [ "${1:-}" = small ]; then
  MESH=tests/data/meshes/armadillo-20k.ply NAME=armadillo20k
else
  MESH=/tmp/armadillo.obj NAME=armadillo
fi
timeout 560 python3 bench/profile_kernels.py --backends warp --mesh "$MESH" --count 100000 --repeats 3 \
  --out "$OUT/profile_kernels_${CARD}_${NAME}_issue48.json" 2>&1 | grep -v "^Warp\|^Module" | tail -40
