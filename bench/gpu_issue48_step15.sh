#!/usr/bin/env bash
# Issue 48, fifteenth step, on the GPU machine after the set-up runs (../shared/device/README.md):
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step15.sh blocks  the armadillo at 100,000 on Warp and numba-cuda
#        with a move launch that is not cooperative in blocks of 64, 128 and 256 threads (the backends'
#        move_block), every launch timed on the device once (move launches split into cooperative and not), then
#        where the device waits (bench/gpu_timeline.py, the set-up's and the final check's steps marked), then
#        both beside numba on the host's 16 cores in one process
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step15.sh turns  the armadillo at 100,000 on Warp and numba-cuda
#        with .gpu2/base's ndpack (git archive BASE ndpack | tar x -C .gpu2/base) and this checkout's in two turns,
#        their spheres side by side
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step15.sh copies  turns (above), then the device store's tests
#        and numba-cuda's on this GPU (numba-cuda's copies into part of an array through the driver)
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step15.sh stack  Warp's move launches on the armadillo at 100,000
#        with Warp as installed and with a copy whose vec_t() leaves its components unset (an experiment, not a fix:
#        every stack() of a walk is a 64-int vec_t, which Warp's generated code zeroes at each call, a 256-byte
#        loop of byte stores in the PTX), each with its own kernel cache, every launch timed once
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step15.sh scale  the armadillo at 100,000 on Warp, numba-cuda and
#        numba on the host's 16 cores in one process, at a million the GPUs in one and numba in the next, then where
#        Warp's device waits, and the final check's overlap search on 1 to 16 threads (bench/verify_speed.py)
# The files gather in one archive under $OUT (a run brings back few files).
set -uo pipefail
source bench/gpu_header.sh
STEP=${STEP:-step15}
issue48_inputs
case "${1:-}" in
  blocks)
    gather_in blocks
    for backend in warp numba-cuda; do
      timeout 200 python3 bench/profile_kernels.py --backends $backend --mesh /tmp/armadillo.obj --count 100000 \
        --variants now block-64 block-128 block-256 --repeats 3 --stages \
        --out "$OUT/blocks_${CARD}_${backend}_issue48_${STEP}.json" 2>&1 | grep -v "^Warp\|^Module" \
        | grep -E "^== |^   (warp|numba-cuda) |move_ids|device kernels"
    done
    for backend in warp numba-cuda; do
      timeout 120 python3 bench/gpu_timeline.py --backend $backend --mesh /tmp/armadillo.obj --count 100000 \
        --out "$OUT/timeline_${CARD}_${backend}_issue48_${STEP}.json" 2>&1 | grep -v "^Warp\|^Module" | head -30
    done
    timeout 150 python3 bench/profile_kernels.py --stages --no-profiled --backends warp numba-cuda numba \
      --mesh /tmp/armadillo.obj --count 100000 --repeats 3 \
      --out "$OUT/armadillo_100k_${CARD}_backends_issue48_${STEP}.json" 2>&1 | grep -E "^== |now: " \
      | grep -v "^Warp\|^Module"
    tar czf "$FINAL/blocks_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  turns|copies)
    need_base "$1"
    gather_in "$1"
    in_turns "armadillo_100k_${CARD}_issue48_${STEP}" armadillo_BACKEND --backends warp numba-cuda --mesh /tmp/armadillo.obj \
      --count 100000 --repeats 3
    same_spheres "$OUT/same_spheres_${CARD}_issue48_${STEP}.txt" armadillo_warp armadillo_numba-cuda
    if [ "$1" = copies ]; then
      timeout 200 python3 -m pytest -q -p no:cacheprovider tests/backends/test_backends.py tests/backends/test_numba_cuda_launch.py \
        -k "small_device or fast_mode or conflict or cuda or replay" 2>&1 | tail -4 | tee "$OUT/gpu_tests_${CARD}_issue48_${STEP}.txt"
    fi
    tar czf "$FINAL/$1_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  stack)
    gather_in stack
    site=$(python3 -c "import warp, os; print(os.path.dirname(os.path.dirname(warp.__file__)))" 2>/dev/null | tail -1)
    rm -rf /tmp/warp-noinit && mkdir -p /tmp/warp-noinit && cp -r "$site/warp" /tmp/warp-noinit/
    python3 - <<'PY'
from pathlib import Path
header = Path("/tmp/warp-noinit/warp/native/vec.h")
text = header.read_text()
old = "    inline CUDA_CALLABLE vec_t()\n        : c()\n    {\n    }"
assert old in text, "vec.h: the default constructor is not as expected"
header.write_text(text.replace(old, "    inline CUDA_CALLABLE vec_t() {}"))
print("patched", header)
PY
    for version in installed noinit; do
      path=$PYTHONPATH
      [ $version = noinit ] && path=/tmp/warp-noinit:$PYTHONPATH
      PYTHONPATH=$path NDPACK_CACHE=/tmp/cache-$version WARP_CACHE_PATH=/tmp/cache-$version/warp timeout 200 \
        python3 bench/profile_kernels.py --backends warp --mesh /tmp/armadillo.obj --count 100000 --repeats 2 \
        --stages --spheres "/tmp/armadillo_stack_$version.npz" \
        --out "$OUT/stack_${CARD}_warp_${version}_issue48_${STEP}.json" 2>&1 | grep -v "^Warp\|^Module" \
        | grep -E "^== |^   warp |move_ids|device kernels"
    done
    python3 -c "
import numpy as np
a, b = (np.load(f'/tmp/armadillo_stack_{v}.npz') for v in ('installed', 'noinit'))
print('same spheres:', len(a['radii']) == len(b['radii']) and bool((a['radii'] == b['radii']).all()))" \
      | tee "$OUT/stack_same_spheres_${CARD}_issue48_${STEP}.txt"
    tar czf "$FINAL/stack_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  scale)
    gather_in scale
    kernels now "armadillo_100k_${CARD}_backends_issue48_${STEP}" --backends warp numba-cuda numba \
      --mesh /tmp/armadillo.obj --count 100000 --repeats 3 | grep -E "^== |now: "
    kernels now "armadillo_1m_${CARD}_gpus_issue48_${STEP}" --backends warp numba-cuda \
      --mesh /tmp/armadillo.obj --count 1000000 --repeats 2 | grep -E "^== |now: "
    kernels now "armadillo_1m_${CARD}_numba_issue48_${STEP}" --backends numba \
      --mesh /tmp/armadillo.obj --count 1000000 --repeats 2 | grep -E "^== |now: "
    timeout 120 python3 bench/gpu_timeline.py --backend warp --mesh /tmp/armadillo.obj --count 100000 \
      --out "$OUT/timeline_${CARD}_warp_issue48_${STEP}_scale.json" 2>&1 | grep -v "^Warp\|^Module" | head -14
    timeout 120 python3 bench/verify_speed.py --count 100000 --backend warp --mesh /tmp/armadillo.obj --repeats 5 \
      --out "$OUT/verify_speed_${CARD}_armadillo_100k_issue48_${STEP}.json" 2>&1 | grep -v "^Warp\|^Module"
    tar czf "$FINAL/scale_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  *) echo "usage: bash bench/gpu_issue48_step15.sh blocks|turns|copies|stack|scale" >&2; exit 2 ;;
esac
