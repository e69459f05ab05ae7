#!/usr/bin/env bash
# Issue 48, ninth step (numba-cuda's first compile: a mesh's own program without the interpreter, device functions
# compiled once per argument types rather than per constant, one converge in the move kernel), on the GPU machine
# after the set-up runs (../shared/device/README.md), with numpy 2.4 carried:
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step9.sh compile  a fresh machine's first numba-cuda packing of
#        the armadillo, kernel by kernel (Numba, NVVM and the link apart), with this checkout (and the heaviest
#        kernels linked again: one after another, in threads, at other levels) and with .gpu2/base (BASE, the commit
#        before the step: git archive BASE ndpack | tar x -C .gpu2/base); Warp's first packing of it
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step9.sh fresh  a fresh machine's first packing of the armadillo,
#        every cache empty (bench/fresh_machine.py): numba-cuda and Warp, this checkout and .gpu2/base
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step9.sh backends  the armadillo at 100,000 on numba-cuda, Warp
#        and numba on the host's cores in one process (3 runs each)
#   source .gpu2/setup.sh && STEP=step9d bash bench/gpu_issue48_step9.sh warp  Warp's move with one converge against
#        .gpu2/base (1b1777e): a fresh machine's first packing of the armadillo on Warp, then the armadillo at
#        100,000 on Warp in turns (3 runs each)
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step9.sh cuda  numba-cuda's tests on the device; the armadillo
#        at 100,000 on numba-cuda with this checkout and .gpu2/base in turns (3 runs each), then numba-cuda, Warp and
#        numba on the host's cores in one process (3 runs each)
set -uo pipefail
source bench/gpu_header.sh
STEP=${STEP:-step9}  # another name for a second run of the same step
issue48_inputs
case "${1:-}" in
  compile)
    need_base compile
    for version in now base; do
      path=$PYTHONPATH study=--link-study
      [ "$version" = base ] && path=$PWD/.gpu2/base:$PYTHONPATH study=
      PYTHONPATH=$path timeout 280 python3 bench/cuda_compile.py --on-gpu --mesh /tmp/armadillo.obj $study \
        --out "$OUT/cuda_compile_${CARD}_issue48_${STEP}_${version}.json" 2>&1 | grep -v "^{\|^Warp"
    done
    cold_first_packing "$OUT/compile_${CARD}_issue48_${STEP}_warp.txt"
    ;;
  fresh)
    need_base fresh
    fresh_runs "fresh_machine_${CARD}_issue48_${STEP}" 400 numba-cuda warp
    ;;
  cuda)
    need_base cuda
    timeout 300 python3 -m pytest -q -p no:cacheprovider tests/backends/test_numba_cuda_lanes.py \
      tests/backends/test_backends.py -k "numba-cuda or device or lanes" 2>&1 | tail -6 \
      | tee "$OUT/gpu_tests_${CARD}_issue48_${STEP}.txt"
    for turn in 1 2; do
      for version in base now; do
        kernels "$version" "armadillo_100k_${CARD}_numba_cuda_issue48_${STEP}_turn${turn}" --backends numba-cuda \
          --mesh /tmp/armadillo.obj --count 100000 --repeats 2
      done
    done
    kernels now "armadillo_100k_${CARD}_backends_issue48_${STEP}" --backends numba-cuda warp numba \
      --mesh /tmp/armadillo.obj --count 100000 --repeats 3
    ;;
  warp)
    need_base warp
    fresh_runs "fresh_machine_${CARD}_issue48_${STEP}" 200 warp
    for turn in 1 2; do
      for version in base now; do
        kernels "$version" "armadillo_100k_${CARD}_warp_issue48_${STEP}_turn${turn}" --backends warp \
          --mesh /tmp/armadillo.obj --count 100000 --repeats 3
      done
    done
    ;;
  backends)
    kernels now "armadillo_100k_${CARD}_backends_issue48_${STEP}" --backends numba-cuda warp numba \
      --mesh /tmp/armadillo.obj --count 100000 --repeats 3
    ;;
  *) echo "usage: bash bench/gpu_issue48_step9.sh compile|fresh|backends|warp|cuda" >&2; exit 2 ;;
esac
