#!/usr/bin/env bash
# A million spheres in the unit cube on the GPU machine, with the GPU's memory sampled twice a
# second (nvidia-smi; it includes the CUDA context). After the set-up runs:
#   source .gpu2/setup.sh && bash bench/gpu_million.sh [backend] [time budget in s]
set -uo pipefail
OUT=${OUT:-/tmp/out}
BACKEND=${1:-warp}
BUDGET=${2:-480}
mkdir -p "$OUT"
nvidia-smi --query-gpu=memory.used --format=csv,noheader,nounits -lms 500 > "$OUT/gpu_memory_$BACKEND.txt" &
SAMPLER=$!
timeout $((BUDGET + 120)) python3 bench/scale.py --cases cube --backends "$BACKEND" --box-count 1000000 \
  --time-budget "$BUDGET" --out "$OUT/scale_million_$BACKEND.json" 2>&1 | grep -v "^Warp\|^Module" | tee "$OUT/million.txt"
kill $SAMPLER
echo "peak GPU memory used (MiB, whole device): $(sort -n "$OUT/gpu_memory_$BACKEND.txt" | tail -1)" | tee -a "$OUT/million.txt"
