#!/usr/bin/env bash
# The GPU machine's part of issue 5 (scale), after the two set-up runs (.gpu1, .gpu2):
#   source .gpu2/setup.sh && bash bench/gpu_scale.sh [path to armadillo.obj or .obj.xz]
# Runs the scale and device-store tests on the GPU backends (unless TESTS=0), then bench/scale.py
# on the armadillo (fast mode, 10,000 and 100,000 spheres) and the unit cube (100,000) for each of
# $BACKENDS (default: numba-cuda, Warp, and numba on 16 threads). Results go to $OUT.
set -uo pipefail
OUT=${OUT:-/tmp/out}
MESH=${1:-.gpu4/armadillo.obj.xz}
BACKENDS=${BACKENDS:-numba-cuda warp numba}
mkdir -p "$OUT"
if [[ "$MESH" == *.xz ]]; then xz -dc "$MESH" > /tmp/armadillo.obj && MESH=/tmp/armadillo.obj; fi
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader | tee "$OUT/gpu.txt"
python3 -c "import numba, numba.cuda, warp; print('numba', numba.__version__, 'warp', warp.__version__)" 2>&1 \
  | tail -1 | tee -a "$OUT/gpu.txt"
if [[ "${TESTS:-1}" == 1 ]]; then
  timeout 300 python3 -m pytest -q -x -p no:cacheprovider tests/test_scale.py tests/backends/test_backends.py -k "device or index" \
    2>&1 | tail -6 | tee "$OUT/scale_tests.txt"
fi
for backend in $BACKENDS; do
  NUMBA_NUM_THREADS=16 timeout 300 python3 bench/scale.py --cases armadillo cube --backends "$backend" \
    --mesh "$MESH" --counts 10000 100000 --faithful-count 0 --box-count 100000 --time-budget 100 \
    --out "$OUT/scale_gpu_$backend.json" 2>&1 | grep -v "^Warp\|^Module" | tee -a "$OUT/scale_gpu.txt"
done
