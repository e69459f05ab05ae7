#!/usr/bin/env bash
# Issue 6 on the GPU machine, after the set-up runs (.gpu1, then .gpu2):
#   source .gpu2/setup.sh && bash bench/gpu_issue6.sh check
#       `ndpack backends` as a user there sees it, and the kernel language's //, % and ** on
#       numba, Warp (CUDA) and numba-cuda (bench/arithmetic_backends.py);
#   bash bench/gpu_issue6.sh render      (a third run, carrying .gpu7: Matplotlib's wheels)
#       the 3-D ray-caster on the host's CPU cores, up to a million spheres (bench/render_speed.py).
set -uo pipefail
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader | tee "$OUT/gpu.txt"
echo "cores: $(nproc)" | tee -a "$OUT/gpu.txt"
case "${1:-check}" in
  check)
    python3 -m ndpack.cli backends 2>&1 | tee "$OUT/backends.txt"
    timeout 300 python3 bench/arithmetic_backends.py --backends numba warp:cuda:0 numba-cuda -n 5000 \
      --out "$OUT/arithmetic_backends_h100.json" 2>&1 | grep -v "^Warp\|^Module" | tee "$OUT/arithmetic.txt" ;;
  render)
    # Matplotlib is not on the GPU machine: install the carried wheels beside run 2's packages.
    python3 -m pip install -q --no-index --no-deps --no-compile --target /tmp/gpu-extra .gpu7/*.whl || exit 1
    export PYTHONPATH=/tmp/gpu-site:/tmp/gpu-extra:$PWD PYTHONUNBUFFERED=1
    timeout 420 python3 bench/render_speed.py --copies 1 10 --out "$OUT/render_speed_h100host.json" 2>&1 \
      | grep -v "^Warp\|^Module" | tee "$OUT/render.txt" ;;
  *) echo "unknown part $1: check or render" >&2; exit 2 ;;
esac
