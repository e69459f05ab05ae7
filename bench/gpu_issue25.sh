#!/usr/bin/env bash
# Issue 25 on the GPU machine (after the set-up runs: source .gpu2/setup.sh && bash bench/gpu_issue25.sh STEP):
#   cpu     parts per minute on 1-16 workers (numba), and the tiled cube against one run, numba
#           on every core, at COUNT spheres (default 1,000,000)
#   gpu     the same cube on the GPU: one run (Warp) against 2 and 4 processes sharing the GPU,
#           with the GPU's memory sampled twice a second
#   big     the tiled cube to BIG spheres (default 10,000,000) on 16 CPU workers, no run alone
# Each step stays under the device tool's 10 minutes; results in $OUT.
set -uo pipefail
source "$(dirname "$0")/gpu_header.sh"
STEP=${1:-cpu}
COUNT=${COUNT:-1000000}
BIG=${BIG:-10000000}
case "$STEP" in
  cpu)
    NDPACK_BACKEND=numba timeout 150 python3 bench/many_parts.py --workers 1 2 4 8 16 --count 2000 --no-meshes \
      --out "$OUT/many_parts_h100.json" 2>&1 | grep -v "^Warp\|^Module"
    timeout -s INT -k 30 380 python3 bench/tiled.py --count "$COUNT" --workers 16 4 --backend numba \
      --out "$OUT/tiled_h100_numba.json" 2>&1 | grep -v "^Warp\|^Module"
    ;;
  gpu)
    nvidia-smi --query-gpu=memory.used --format=csv,noheader,nounits -lms 500 > "$OUT/gpu_memory_tiled.txt" &
    SAMPLER=$!
    timeout -s INT -k 30 520 python3 bench/tiled.py --count "$COUNT" --workers 2 4 --backend warp --device cuda:0 \
      --out "$OUT/tiled_h100_warp.json" 2>&1 | grep -v "^Warp\|^Module"
    kill $SAMPLER
    echo "peak GPU memory used (MiB, whole device): $(sort -n "$OUT/gpu_memory_tiled.txt" | tail -1)"
    ;;
  big)
    timeout -s INT -k 30 520 python3 bench/tiled.py --count "$BIG" --workers 16 --backend numba --no-alone \
      --out "$OUT/tiled_h100_numba_big.json" 2>&1 | grep -v "^Warp\|^Module"
    ;;
esac
