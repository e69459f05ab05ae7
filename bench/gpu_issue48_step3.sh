#!/usr/bin/env bash
# Issue 48, third step (cooperative walks, ndpack.backends.warp_lanes), on the GPU machine after the
# set-up runs (../shared/device/README.md):
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step3.sh lanes     a fresh machine's first packing of
#        the armadillo (caches and the driver's cache off: the module is larger); then the armadillo at
#        100,000: cooperative walks in move launches of at most 4,096 prototypes (now) against never
#        (lanes-off) and at most 1,024, 8,192 and 16,384; every launch timed in a second run; numba on the
#        host's cores beside them
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step3.sh million   the armadillo at 1,000,000, now and
#        lanes-off (2 runs each)
set -uo pipefail
source bench/gpu_header.sh
[ -f /tmp/armadillo.obj ] || xz -dc .gpu2/armadillo.obj.xz > /tmp/armadillo.obj
CARD=$(nvidia-smi --query-gpu=name --format=csv,noheader | head -1 | grep -o 'H[0-9][0-9]*' | head -1 | tr H h)  # h100, h200
case "${1:-}" in
  lanes)
    (export NDPACK_CACHE=/tmp/ndpack-cold-cache WARP_CACHE_PATH=/tmp/ndpack-cold-cache/warp CUDA_CACHE_DISABLE=1
     rm -rf /tmp/ndpack-cold-cache
     python3 - <<'PY' 2>&1 | grep -v "^Warp\|^Module" | tee "$OUT/compile_${CARD}_issue48_step3.txt"
import time
import ndpack as nd
shape = nd.TriangleMesh.load("/tmp/armadillo.obj")
started = time.perf_counter()
nd.pack(shape, 3, backend="warp", mode="fast", progress=False)
first = time.perf_counter() - started
started = time.perf_counter()
nd.pack(shape, 3, backend="warp", mode="fast", progress=False)
print(f"warp, cuda: first packing of a mesh, cache empty: {first:.1f} s; the next: {time.perf_counter() - started:.2f} s")
PY
    )
    export NDPACK_CACHE=/tmp/ndpack-gpu-cache WARP_CACHE_PATH=/tmp/ndpack-gpu-cache/warp
    timeout 420 python3 bench/profile_kernels.py --backends warp --mesh /tmp/armadillo.obj --count 100000 \
      --repeats 3 --stages --variants now lanes-off lanes-1024 lanes-8192 lanes-16384 \
      --out "$OUT/profile_kernels_${CARD}_armadillo_issue48_step3.json" 2>&1 | grep -v "^Warp\|^Module" | tail -90
    timeout 150 python3 bench/profile_kernels.py --backends numba --mesh /tmp/armadillo.obj --count 100000 \
      --repeats 3 --stages --no-profiled --out "$OUT/profile_kernels_${CARD}host_numba_armadillo_issue48_step3.json" \
      2>&1 | grep -v "^Warp\|^Module"
    ;;
  million)
    export NDPACK_CACHE=/tmp/ndpack-gpu-cache WARP_CACHE_PATH=/tmp/ndpack-gpu-cache/warp
    timeout 300 python3 bench/profile_kernels.py --backends warp --mesh /tmp/armadillo.obj --count 1000000 --repeats 2 \
      --stages --no-profiled --variants now lanes-off --out "$OUT/million_${CARD}_armadillo_issue48_step3.json" \
      2>&1 | grep -v "^Warp\|^Module"
    ;;
  *) echo "usage: bash bench/gpu_issue48_step3.sh lanes|million" >&2; exit 2 ;;
esac
