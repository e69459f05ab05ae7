#!/usr/bin/env bash
# The rest of issue 5's benchmark rows on the GPU machine, one part a command (each fits the
# device's 10-minute limit). After the set-up runs (.gpu1, .gpu2):
#   source .gpu2/setup.sh && bash bench/gpu_extra.sh PART BACKEND [path to armadillo.obj or .obj.xz]
# PART is one of
#   boxes       unit square and unit cube to 1,000,000 spheres (fill against count, exponent)
#   nd          4-, 5- and 6-D balls with a hole, to 100,000 spheres
#   subdivided  the armadillo subdivided once (about 400,000 triangles) to 10,000, 100,000, 1,000,000
# with the GPU's memory sampled twice a second (nvidia-smi, whole device). Results go to $OUT.
set -uo pipefail
OUT=${OUT:-/tmp/out}
PART=$1
BACKEND=${2:-warp}
MESH=${3:-.gpu4/armadillo.obj.xz}
mkdir -p "$OUT"
if [[ "$MESH" == *.xz ]]; then xz -dc "$MESH" > /tmp/armadillo.obj && MESH=/tmp/armadillo.obj; fi
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader | tee "$OUT/gpu.txt"
nvidia-smi --query-gpu=memory.used --format=csv,noheader,nounits -lms 500 > "$OUT/gpu_memory_${PART}_$BACKEND.txt" &
SAMPLER=$!
case "$PART" in
  boxes) ARGS=(--cases square cube --box-count 1000000 --time-budget 200) ;;
  nd) ARGS=(--cases nd --nd-count 100000 --time-budget 110) ;;
  subdivided) ARGS=(--cases armadillo-subdivided --mesh "$MESH" --counts 10000 100000 1000000 --faithful-count 0
                    --time-budget 200) ;;
  *) echo "unknown part $PART: boxes, nd or subdivided" >&2; kill $SAMPLER; exit 2 ;;
esac
timeout 560 python3 bench/scale.py "${ARGS[@]}" --backends "$BACKEND" --out "$OUT/scale_${PART}_$BACKEND.json" 2>&1 \
  | grep -v "^Warp\|^Module" | cut -c1-600 | tee "$OUT/${PART}_$BACKEND.txt"
kill $SAMPLER
echo "peak GPU memory used (MiB, whole device): $(sort -n "$OUT/gpu_memory_${PART}_$BACKEND.txt" | tail -1)" \
  | tee -a "$OUT/${PART}_$BACKEND.txt"
