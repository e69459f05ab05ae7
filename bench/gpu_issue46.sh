#!/usr/bin/env bash
# Issue 46 (one page of today's figures) on the GPU machine, after the set-up runs: a million spheres
# in the 100k-triangle armadillo and in the unit cube (bench/scale.py), on Warp (cuda:0) and on
# numba on the same host's cores, at this commit. .gpu2 carries the armadillo, made here with
#   xz -9 -c ../shared/data/meshes/armadillo.obj > .gpu2/armadillo.obj.xz
# (the GPU image's own numpy 2.5 serves: numba-cuda, which needs 2.4, is not run).
#   source .gpu2/setup.sh && bash bench/gpu_issue46.sh warp     Warp, both shapes
#   source .gpu2/setup.sh && bash bench/gpu_issue46.sh numba    numba on the host's cores, both shapes
# (bench/results/scale_million_h100_warp_issue46.json also holds a faithful run to 10,000 in the armadillo:
# it was made before --faithful-count 0 was added here.)
set -uo pipefail
source bench/gpu_header.sh
[ -f /tmp/armadillo.obj ] || xz -dc .gpu2/armadillo.obj.xz > /tmp/armadillo.obj
export NDPACK_CACHE=/tmp/ndpack-gpu-cache WARP_CACHE_PATH=/tmp/ndpack-gpu-cache/warp
BACKEND=${1:-warp}
timeout 560 python3 bench/scale.py --cases armadillo cube --backends "$BACKEND" --mesh /tmp/armadillo.obj \
  --counts 1000000 --box-count 1000000 --faithful-count 0 --out "$OUT/scale_million_h100_${BACKEND}_issue46.json" 2>&1 \
  | grep -v "^Warp\|^Module" | tee "$OUT/scale_million_$BACKEND.txt"
