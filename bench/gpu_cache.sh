#!/usr/bin/env bash
# The kernel cache on the GPU machine, after the set-up runs (.gpu1, then .gpu2):
#   source .gpu2/setup.sh && bash bench/gpu_cache.sh
# Cold and warm processes for numba, Warp (cuda:0) and numba-cuda on the 100k-triangle
# armadillo (bench/compile_cache.py), then the GPU tests.
set -uo pipefail
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader | tee "$OUT/gpu.txt"
MESH=../shared/data/meshes/armadillo.obj
[ -f "$MESH" ] || MESH=tests/data/meshes/armadillo-20k.ply
timeout 420 python3 bench/compile_cache.py --backends numba warp:cuda:0 numba-cuda --shape "$MESH" -n 10000 \
  --runs 2 --out "$OUT/compile_cache_h100.json" 2>&1 | grep -v "^Warp\|^Module" | tee "$OUT/compile_cache.txt"
timeout 150 python3 -m pytest -q -p no:cacheprovider tests/test_backends.py -k "numba-cuda" 2>&1 | tail -5 | tee "$OUT/tests.txt"
