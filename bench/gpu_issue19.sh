#!/usr/bin/env bash
# Issue 19 (compile once) on the GPU machine, after the set-up runs (.gpu1, then .gpu2):
#   source .gpu2/setup.sh && bash bench/gpu_issue19.sh start     whole `ndpack pack` processes from a
#       fresh kernel cache: the armadillo (20k triangles), then a new mesh (fandisk), each twice, on
#       Warp (cuda:0), numba-cuda and numba on the host's cores (bench/compile_cache.py)
#   source .gpu2/setup.sh && bash bench/gpu_issue19.sh speed     the tape against specialised code:
#       distances per second and packing time on the same backends (bench/tape_speed.py)
#   source .gpu2/setup.sh && bash bench/gpu_issue19.sh tests     the GPU backends' tests, the
#       compile-nothing test included
set -uo pipefail
source bench/gpu_header.sh
# The start-up part keeps its caches here (the numba-cuda one: the folder 1); the later parts
# load from it instead of compiling again.
CACHE=/tmp/ndpack-gpu-cache
export NDPACK_CACHE=$CACHE/1 WARP_CACHE_PATH=$CACHE/0/warp-binaries
case "${1:-start}" in
  start)
    timeout 560 python3 bench/compile_cache.py --backends warp:cuda:0 numba-cuda numba --scenario meshes \
      --mesh tests/data/meshes/armadillo-20k.ply -n 10000 --cache $CACHE --out "$OUT/compile_cache_h100.json" 2>&1 \
      | grep -v "^Warp\|^Module" | tee "$OUT/compile_cache.txt" ;;
  speed)
    timeout 560 python3 bench/tape_speed.py --backends warp:cuda:0 numba-cuda numba --points 2000000 \
      --spheres 20000 --repeats 3 --shapes demo deep mesh --out "$OUT/tape_speed_h100.json" 2>&1 | grep -v "^Warp\|^Module" \
      | tee "$OUT/tape_speed.txt" ;;
  tests)
    timeout 560 python3 -m pytest -q -p no:cacheprovider tests/backends/test_backends.py tests/kernels/test_compile_cache.py \
      -k "numba-cuda or warp or cuda" 2>&1 | tail -15 | tee "$OUT/tests.txt" ;;
  *) echo "unknown part $1: start, speed or tests" >&2; exit 2 ;;
esac
