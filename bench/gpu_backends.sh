#!/usr/bin/env bash
# The GPU machine's part of issue 3 (see docs/benchmarks.md). Each step is its own argument, so
# one device run can take a few of them:
#   source .gpu2/setup.sh && bash bench/gpu_backends.sh tests profile cube3d
#   source .gpu2/setup.sh && bash bench/gpu_backends.sh shell6d
# tests:   the backend test file on both GPU backends
# profile: where a round's time goes (bench/profile_rounds.py)
# <case>:  bench/backends.py on numba (16 threads), numba-cuda and warp, batch 1 and 64, with
#          Warp's and ndpack's kernel caches empty, so compile_s is a cold compile.
# Results go to $OUT.
set -uo pipefail
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader | tee "$OUT/gpu.txt"
for item in "$@"; do
  case "$item" in
    tests)
      timeout 300 python3 -m pytest -q -x -p no:cacheprovider tests/backends/test_backends.py 2>&1 | tail -15 | tee "$OUT/tests.txt" ;;
    profile)
      timeout 120 python3 bench/profile_rounds.py --backends warp numba-cuda numba --count 3000 2>&1 | tee "$OUT/profile.txt"
      timeout 120 python3 bench/profile_rounds.py --backends warp numba-cuda --count 3000 --kernels 2>&1 | tee -a "$OUT/profile.txt"
      timeout 200 python3 bench/profile_rounds.py --backends warp numba-cuda --count 20000 --batch 64 --kernels 2>&1 | tee -a "$OUT/profile.txt" ;;
    *)
      cold=$(mktemp -d)
      WARP_CACHE_PATH="$cold/warp" NDPACK_CACHE="$cold/ndpack" NUMBA_NUM_THREADS=16 \
        python3 bench/backends.py --cases "$item" --backends numba numba-cuda warp --batch 1 64 \
        --threads 16 --budget 40 --out "$OUT/backends_$item.json" ;;
  esac
done
