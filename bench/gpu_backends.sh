#!/usr/bin/env bash
# The GPU machine's part of issue 3, in one run per case (see docs/benchmarks.md):
#   source .gpu2/setup.sh && bash bench/gpu_backends.sh tests cube3d     (then: shell6d)
# "tests" first runs the backend test file on both GPU backends. Results go to $OUT.
set -uo pipefail
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader | tee "$OUT/gpu.txt"
for item in "$@"; do
  if [ "$item" = tests ]; then
    timeout 240 python3 -m pytest -q -x -p no:cacheprovider tests/test_backends.py 2>&1 | tail -15 | tee "$OUT/tests.txt"
  else
    python3 bench/backends.py --cases "$item" --backends numba numba-cuda warp --batch 1 64 \
      --threads 16 --budget 40 --out "$OUT/backends_$item.json"
    python3 bench/backends.py --cases "$item" --backends numpy --counts 10000 --batch 1 \
      --budget 75 --out "$OUT/backends_${item}_numpy.json"
  fi
done
