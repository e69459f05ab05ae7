#!/usr/bin/env bash
# Issue 48 on the GPU machine, after the set-up runs (../shared/device/README.md): what the work
# model (bench/work_model.py, on the CPU) is checked against. The armadillo at 100,000 spheres on
# Warp (cuda:0), fast mode, seed 0: every launch timed on the device (bench/profile_kernels.py),
# and three unprofiled runs.
#   source .gpu2/setup.sh && bash bench/gpu_issue48.sh
set -uo pipefail
source bench/gpu_header.sh
[ -f /tmp/armadillo.obj ] || xz -dc .gpu2/armadillo.obj.xz > /tmp/armadillo.obj
export NDPACK_CACHE=/tmp/ndpack-gpu-cache WARP_CACHE_PATH=/tmp/ndpack-gpu-cache/warp
timeout 560 python3 bench/profile_kernels.py --backends warp --mesh /tmp/armadillo.obj --count 100000 --repeats 3 \
  --out "$OUT/profile_kernels_h100_armadillo_issue48.json" 2>&1 | grep -v "^Warp\|^Module" | tail -40
