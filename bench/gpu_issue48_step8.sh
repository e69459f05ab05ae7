#!/usr/bin/env bash
# Issue 48, eighth step (numba-cuda's cooperative walk: ndpack.backends.numba_cuda_lanes), on the GPU machine
# after the set-up runs (../shared/device/README.md), with numpy 2.4 carried (bash bench/gpu_stage_numpy.sh
# before run 1: the image's 2.5 breaks numba-cuda's CUDA target):
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step8.sh cuda  the cooperative walk's tests and the backends'
#        numba-cuda tests on the device; the armadillo at 100,000 on numba-cuda with cooperative moves and without
#        (lanes-off: the same kernels' serial path) in one process, .gpu2/base's numba-cuda (BASE, the commit
#        before the step: git archive BASE ndpack | tar x -C .gpu2/base), then Warp and numba on the host's
#        cores in one process (3 runs each)
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step8.sh compile  a fresh machine's first numba-cuda packing
#        of the armadillo, kernel by kernel, with this checkout and with .gpu2/base (bench/cuda_compile.py --on-gpu)
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step8.sh million  numba-cuda beside Warp at 1,000,000 in one
#        process each: the armadillo, the unit cube and the unit square (2 runs)
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step8.sh backends  the armadillo at 100,000 on numba-cuda, Warp
#        and numba on the host's cores in one process (3 runs each); numba-cuda's peak GPU memory at 1,000,000
#        (bench/gpu_issue48_step5.sh memory)
set -uo pipefail
source bench/gpu_header.sh
STEP=${STEP:-step8}  # another name for a second run of the same step
issue48_inputs
case "${1:-}" in
  cuda)
    need_base cuda
    timeout 420 python3 -m pytest -q -p no:cacheprovider tests/backends/test_numba_cuda_lanes.py \
      tests/backends/test_backends.py -k "numba-cuda or device or lanes" 2>&1 | tail -8 \
      | tee "$OUT/gpu_tests_${CARD}_issue48_${STEP}.txt"
    kernels now "armadillo_100k_${CARD}_numba_cuda_issue48_${STEP}" --backends numba-cuda --mesh /tmp/armadillo.obj \
      --count 100000 --repeats 3 --variants now lanes-off
    kernels base "armadillo_100k_${CARD}_numba_cuda_issue48_${STEP}" --backends numba-cuda --mesh /tmp/armadillo.obj \
      --count 100000 --repeats 3
    kernels now "armadillo_100k_${CARD}_backends_issue48_${STEP}" --backends warp numba --mesh /tmp/armadillo.obj \
      --count 100000 --repeats 3
    ;;
  compile)
    need_base compile
    for version in now base; do
      path=$PYTHONPATH
      [ "$version" = base ] && path=$PWD/.gpu2/base:$PYTHONPATH
      PYTHONPATH=$path timeout 280 python3 bench/cuda_compile.py --on-gpu --mesh /tmp/armadillo.obj \
        --out "$OUT/cuda_compile_${CARD}_issue48_${STEP}_${version}.json" 2>&1 | grep -v "^{\|^Warp"
    done
    ;;
  million)
    kernels now "armadillo_1m_${CARD}_backends_issue48_${STEP}" --backends warp numba-cuda --mesh /tmp/armadillo.obj \
      --count 1000000 --repeats 2
    kernels now "cube_1m_${CARD}_backends_issue48_${STEP}" --backends warp numba-cuda --count 1000000 --repeats 2
    kernels now "square_1m_${CARD}_backends_issue48_${STEP}" --backends warp numba-cuda --square --count 1000000 \
      --repeats 2
    ;;
  backends)
    kernels now "armadillo_100k_${CARD}_backends_issue48_${STEP}b" --backends numba-cuda warp numba \
      --mesh /tmp/armadillo.obj --count 100000 --repeats 3
    STEP=$STEP BACKEND=numba-cuda bash bench/gpu_issue48_step5.sh memory
    ;;
  *) echo "usage: bash bench/gpu_issue48_step8.sh cuda|compile|million|backends" >&2; exit 2 ;;
esac
