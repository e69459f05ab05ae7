#!/usr/bin/env bash
# Issue 48, fourth step (cooperative walks in the set-up too, ndpack.backends.warp_lanes), on the GPU
# machine after the set-up runs (../shared/device/README.md):
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step4.sh lanes     a fresh machine's first packing of
#        the armadillo (caches and the driver's cache off: the module is larger); then the armadillo at
#        100,000: cooperative walks (moves of at most 4,096 prototypes, the set-up's converge of at most
#        8,192: now) against never (lanes-off), not in the set-up (converge-off) and moves of at most 8,192;
#        every launch timed in a second run; numba on the host's cores beside them
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step4.sh million   the armadillo at 1,000,000, now and
#        lanes-off (2 runs each)
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step4.sh share     the armadillo at 100,000, the lanes
#        agreeing on the best distance every 1, 4 and 16 rounds (4 runs each: the first compiles)
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step4.sh where     the first packing and each module's cold
#        compile time, and the armadillo at 1,000,000 with every launch timed
set -uo pipefail
source bench/gpu_header.sh
[ -f /tmp/armadillo.obj ] || xz -dc .gpu2/armadillo.obj.xz > /tmp/armadillo.obj
# Step 3 (bench/gpu_issue48_step3.sh) is this script with its own name and variants.
STEP=${STEP:-step4}
VARIANTS=${VARIANTS:-now lanes-off converge-off lanes-8192}
case "${1:-}" in
  lanes)
    cold_first_packing "$OUT/compile_${CARD}_issue48_${STEP}.txt"
    export NDPACK_CACHE=/tmp/ndpack-gpu-cache WARP_CACHE_PATH=/tmp/ndpack-gpu-cache/warp
    timeout 420 python3 bench/profile_kernels.py --backends warp --mesh /tmp/armadillo.obj --count 100000 \
      --repeats 3 --stages --variants $VARIANTS \
      --out "$OUT/profile_kernels_${CARD}_armadillo_issue48_${STEP}.json" 2>&1 | grep -v "^Warp\|^Module" | tail -90
    timeout 150 python3 bench/profile_kernels.py --backends numba --mesh /tmp/armadillo.obj --count 100000 \
      --repeats 3 --stages --no-profiled --out "$OUT/profile_kernels_${CARD}host_numba_armadillo_issue48_${STEP}.json" \
      2>&1 | grep -v "^Warp\|^Module"
    ;;
  million)
    export NDPACK_CACHE=/tmp/ndpack-gpu-cache WARP_CACHE_PATH=/tmp/ndpack-gpu-cache/warp
    timeout 300 python3 bench/profile_kernels.py --backends warp --mesh /tmp/armadillo.obj --count 1000000 --repeats 2 \
      --stages --no-profiled --variants now lanes-off --out "$OUT/million_${CARD}_armadillo_issue48_${STEP}.json" \
      2>&1 | grep -v "^Warp\|^Module"
    ;;
  share)
    export NDPACK_CACHE=/tmp/ndpack-gpu-cache WARP_CACHE_PATH=/tmp/ndpack-gpu-cache/warp
    timeout 300 python3 bench/profile_kernels.py --backends warp --mesh /tmp/armadillo.obj --count 100000 \
      --repeats 4 --stages --variants share-1 share-4 share-16 \
      --out "$OUT/share_${CARD}_armadillo_issue48_${STEP}.json" 2>&1 | grep -v "^Warp\|^Module" | grep "==\|move_ids\|against"
    ;;
  where)
    # Each module's cold compile time, as the notices will quote it next time (the cold cache's
    # compile-times.json), and where a million's time goes (every launch timed, once).
    cold_first_packing "$OUT/compile_${CARD}_issue48_${STEP}.txt"
    tee "$OUT/compile_times_${CARD}_issue48_${STEP}.json" < /tmp/ndpack-cold-cache/compile-times.json
    export NDPACK_CACHE=/tmp/ndpack-gpu-cache WARP_CACHE_PATH=/tmp/ndpack-gpu-cache/warp
    timeout 300 python3 bench/profile_kernels.py --backends warp --mesh /tmp/armadillo.obj --count 1000000 \
      --repeats 1 --stages --out "$OUT/profile_kernels_${CARD}_armadillo_1m_issue48_${STEP}.json" 2>&1 \
      | grep -v "^Warp\|^Module" | tail -40
    ;;
  *) echo "usage: bash bench/gpu_issue48_step4.sh lanes|million|share|where" >&2; exit 2 ;;
esac
