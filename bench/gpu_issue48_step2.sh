#!/usr/bin/env bash
# Issue 48, second step, on the GPU machine after the set-up runs (../shared/device/README.md).
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step2.sh compile   the first compile, cache cold
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step2.sh armadillo the armadillo at 100,000: Warp now
#        (split ratio SPLIT_RATIO_AHEAD) against split-4 (the ratio before), stages timed, every launch
#        timed in a second run; numba on the host's cores beside them
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step2.sh million   the cube and the armadillo at
#        1,000,000 on Warp (3 and 2 runs), the cube on numba on the host's cores (one run)
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step2.sh square    the unit square at 1,000,000: Warp
#        (2 runs), numba on the host's cores (one run)
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step2.sh first     a process's first packing of the
#        armadillo at 100,000 against its next ones (bench/first_run.py)
set -uo pipefail
source bench/gpu_header.sh
[ -f /tmp/armadillo.obj ] || xz -dc .gpu2/armadillo.obj.xz > /tmp/armadillo.obj
case "${1:-}" in
  compile)
    # A fresh machine's first packing of a mesh (since the cooperative walks' step, with the driver's
    # cache off too: bench/gpu_header.sh).
    cold_first_packing "$OUT/compile_${CARD}_issue48.txt"
    ;;
  armadillo)
    export NDPACK_CACHE=/tmp/ndpack-gpu-cache WARP_CACHE_PATH=/tmp/ndpack-gpu-cache/warp
    timeout 400 python3 bench/profile_kernels.py --backends warp --mesh /tmp/armadillo.obj --count 100000 \
      --repeats 3 --stages --variants now split-4 --out "$OUT/profile_kernels_${CARD}_armadillo_issue48_step2.json" \
      2>&1 | grep -v "^Warp\|^Module" | tail -70
    timeout 150 python3 bench/profile_kernels.py --backends numba --mesh /tmp/armadillo.obj --count 100000 \
      --repeats 3 --stages --no-profiled --out "$OUT/profile_kernels_${CARD}host_numba_armadillo_issue48_step2.json" \
      2>&1 | grep -v "^Warp\|^Module"
    ;;
  million)
    export NDPACK_CACHE=/tmp/ndpack-gpu-cache WARP_CACHE_PATH=/tmp/ndpack-gpu-cache/warp
    timeout 150 python3 bench/profile_kernels.py --backends warp --count 1000000 --repeats 3 --stages --no-profiled \
      --out "$OUT/million_${CARD}_cube_issue48_step2.json" 2>&1 | grep -v "^Warp\|^Module"
    timeout 150 python3 bench/profile_kernels.py --backends warp --mesh /tmp/armadillo.obj --count 1000000 --repeats 2 \
      --stages --no-profiled --out "$OUT/million_${CARD}_armadillo_issue48_step2.json" 2>&1 | grep -v "^Warp\|^Module"
    timeout 120 python3 bench/profile_kernels.py --backends numba --count 1000000 --repeats 1 --stages --no-profiled \
      --out "$OUT/million_${CARD}host_numba_cube_issue48_step2.json" 2>&1 | grep -v "^Warp\|^Module"
    ;;
  square)
    export NDPACK_CACHE=/tmp/ndpack-gpu-cache WARP_CACHE_PATH=/tmp/ndpack-gpu-cache/warp
    timeout 150 python3 bench/profile_kernels.py --backends warp --square --count 1000000 --repeats 2 --stages \
      --no-profiled --out "$OUT/million_${CARD}_square_issue48_step2.json" 2>&1 | grep -v "^Warp\|^Module"
    timeout 150 python3 bench/profile_kernels.py --backends numba --square --count 1000000 --repeats 1 --stages \
      --no-profiled --out "$OUT/million_${CARD}host_numba_square_issue48_step2.json" 2>&1 | grep -v "^Warp\|^Module"
    ;;
  first)
    export NDPACK_CACHE=/tmp/ndpack-gpu-cache WARP_CACHE_PATH=/tmp/ndpack-gpu-cache/warp
    timeout 150 python3 bench/first_run.py --mesh /tmp/armadillo.obj --count 100000 --backend warp --repeats 3 \
      --out "$OUT/first_run_${CARD}_armadillo_issue48.json" 2>&1 | grep -v "^Warp\|^Module"
    ;;
  *) echo "usage: bash bench/gpu_issue48_step2.sh compile|armadillo|million|square|first" >&2; exit 2 ;;
esac
