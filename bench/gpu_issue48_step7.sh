#!/usr/bin/env bash
# Issue 48, seventh step (a round's host work: the late finds' rule in the window's query, on the device;
# answers' first copies sized from their kernel's last two; pinned buffers' numpy views kept; the polish
# ahead reaching down to (1 - FAST_WINDOW)**3 of the frontier, rounds.POLISH_AHEAD), on the GPU machine
# after the set-up runs (../shared/device/README.md):
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step7.sh measure  this checkout against the one in
#        .gpu2/base (BASE, the commit before the step: git archive BASE ndpack | tar x -C .gpu2/base), in one
#        run: the armadillo at 100,000 with each in turn, twice (5 runs each), numba on the host's cores
#        (3 runs), this checkout with the polish ahead's old reach beside its own in one process (3 runs
#        each); the armadillo and the unit cube at 1,000,000 (2 runs each, both checkouts), the unit square
#        at 1,000,000 (2 runs); then one profiled run at 100,000 (every launch timed, and the host's
#        cProfile); the files in one archive, $OUT/measure_CARD_issue48_step7.tgz
#   source .gpu2/setup.sh && STEP=step7b bash bench/gpu_issue48_step7.sh final  this checkout's figures, on
#        another lease: a fresh machine's first packing of a mesh; the armadillo at 100,000 with .gpu2/base's
#        ndpack and this checkout's in turn (5 runs each), numba on the host's cores (3 runs); the armadillo,
#        the unit cube and the unit square at 1,000,000 (2 runs each), numba on the cube and the square at
#        1,000,000 (one run each); peak GPU memory at a million (bench/gpu_issue48_step5.sh memory)
#   source .gpu2/setup.sh && STEP=step7c bash bench/gpu_issue48_step7.sh cuda  numba-cuda on the GPU (numpy 2.4, by
#        bash bench/gpu_stage_numpy.sh before run 1,
#        carried: the image's 2.5 breaks its CUDA target): the backends' tests on the device, then the armadillo
#        at 100,000 on Warp, numba-cuda and numba on the host's cores in one process (3 runs each)
#   source .gpu2/setup.sh && STEP=step7c bash bench/gpu_issue48_step7.sh cuda-million  numba-cuda beside Warp at
#        1,000,000 in one process each (numpy 2.4 carried): the armadillo, the unit cube and the unit square (2 runs)
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step7.sh cuda-compile  numba-cuda's first compile of a mesh's
#        kernels with NVVM's optimisation and without (bench/compile_options.py), and the armadillo at 100,000 with each
set -uo pipefail
source bench/gpu_header.sh
STEP=${STEP:-step7}  # another name for a second run of the same step
issue48_inputs
case "${1:-}" in
  measure)
    need_base measure
    gather_in measure
    turns "armadillo_100k_${CARD}_issue48_${STEP}" 2
    kernels now "armadillo_100k_${CARD}host_numba_issue48_${STEP}" --backends numba --mesh /tmp/armadillo.obj \
      --count 100000 --repeats 3
    kernels now "armadillo_100k_${CARD}_issue48_${STEP}_reach" --backends warp --mesh /tmp/armadillo.obj \
      --count 100000 --repeats 3 --variants now reach-0.64
    for version in base now; do
      kernels $version "armadillo_1m_${CARD}_issue48_${STEP}" --backends warp --mesh /tmp/armadillo.obj \
        --count 1000000 --repeats 2
      kernels $version "cube_1m_${CARD}_issue48_${STEP}" --backends warp --count 1000000 --repeats 2
    done
    kernels now "square_1m_${CARD}_issue48_${STEP}" --backends warp --square --count 1000000 --repeats 2
    timeout 300 python3 bench/profile_kernels.py --backends warp --mesh /tmp/armadillo.obj --count 100000 \
      --repeats 1 --stages --host-profile --out "$OUT/profile_kernels_${CARD}_armadillo_issue48_${STEP}.json" 2>&1 \
      | grep -v "^Warp\|^Module\|^ndpack: compiling" > "$OUT/profile_kernels_${CARD}_armadillo_issue48_${STEP}.txt"
    tail -5 "$OUT/profile_kernels_${CARD}_armadillo_issue48_${STEP}.txt"
    tar czf "$FINAL/measure_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  final)
    need_base final
    cold_first_packing "$OUT/compile_${CARD}_issue48_${STEP}.txt"
    for version in base now; do
      kernels $version "armadillo_100k_${CARD}_issue48_${STEP}" --backends warp --mesh /tmp/armadillo.obj \
        --count 100000 --repeats 5
    done
    kernels now "armadillo_100k_${CARD}host_numba_issue48_${STEP}" --backends numba --mesh /tmp/armadillo.obj \
      --count 100000 --repeats 3
    kernels now "armadillo_1m_${CARD}_issue48_${STEP}" --backends warp --mesh /tmp/armadillo.obj \
      --count 1000000 --repeats 2
    kernels now "cube_1m_${CARD}_issue48_${STEP}" --backends warp --count 1000000 --repeats 2
    kernels now "square_1m_${CARD}_issue48_${STEP}" --backends warp --square --count 1000000 --repeats 2
    kernels now "cube_1m_${CARD}host_numba_issue48_${STEP}" --backends numba --count 1000000 --repeats 1
    kernels now "square_1m_${CARD}host_numba_issue48_${STEP}" --backends numba --square --count 1000000 --repeats 1
    bash bench/gpu_issue48_step5.sh memory
    ;;
  cuda)
    timeout 300 python3 -m pytest -q -p no:cacheprovider tests/backends/test_backends.py -k "numba-cuda or device" \
      2>&1 | tail -6 | tee "$OUT/gpu_tests_${CARD}_issue48_${STEP}.txt"
    kernels now "armadillo_100k_${CARD}_backends_issue48_${STEP}" --backends warp numba-cuda numba \
      --mesh /tmp/armadillo.obj --count 100000 --repeats 3
    ;;
  cuda-million)
    kernels now "armadillo_1m_${CARD}_backends_issue48_${STEP}" --backends warp numba-cuda --mesh /tmp/armadillo.obj \
      --count 1000000 --repeats 2
    kernels now "cube_1m_${CARD}_backends_issue48_${STEP}" --backends warp numba-cuda --count 1000000 --repeats 2
    kernels now "square_1m_${CARD}_backends_issue48_${STEP}" --backends warp numba-cuda --square --count 1000000 \
      --repeats 2
    ;;
  cuda-compile)
    timeout 500 python3 bench/compile_options.py --backend numba-cuda --mesh /tmp/armadillo.obj \
      --variants ndpack cuda-noopt --out "$OUT/compile_options_${CARD}_numba_cuda_issue48.json" 2>&1 | grep -v "^Warp"
    ;;
  *) echo "usage: bash bench/gpu_issue48_step7.sh measure|final|cuda|cuda-million|cuda-compile" >&2; exit 2 ;;
esac
