#!/usr/bin/env bash
# Issue 48, thirteenth step, on the GPU machine after the set-up runs (../shared/device/README.md), with numpy 2.4
# carried:
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step13.sh check  the armadillo at 100,000 on Warp and numba-cuda,
#        this checkout (the final check's centre distances computed while the rounds run:
#        ndpack.drivers.greedy.centre_distances) against .gpu2/base in two turns, their spheres side by side; then the
#        three backends in one process (numba on the host's cores) and the device store's tests
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step13.sh million  the armadillo and the unit cube at 1,000,000 on
#        Warp, this checkout against .gpu2/base in two turns
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step13.sh timeline  where the device waits for the host: the
#        armadillo at 100,000 on Warp and numba-cuda, every kernel timed by CUPTI through PyTorch's profiler and the
#        host's driver steps marked (bench/gpu_timeline.py)
# The files gather in one archive under $OUT (a run brings back few files).
set -uo pipefail
source bench/gpu_header.sh
STEP=${STEP:-step13}
issue48_inputs
case "${1:-}" in
  check)
    need_base check
    gather_in check
    in_turns "armadillo_100k_${CARD}_issue48_${STEP}" armadillo_BACKEND --backends warp numba-cuda \
      --mesh /tmp/armadillo.obj --count 100000 --repeats 3
    same_spheres "$OUT/same_spheres_${CARD}_issue48_${STEP}.txt" armadillo_warp armadillo_numba-cuda
    beside_and_store_tests "armadillo_100k_${CARD}_backends_issue48_${STEP}"
    tar czf "$FINAL/check_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  million)
    need_base million
    gather_in million
    in_turns "armadillo_1m_${CARD}_warp_issue48_${STEP}" armadillo_1m_BACKEND --backends warp \
      --mesh /tmp/armadillo.obj --count 1000000 --repeats 1
    in_turns "cube_1m_${CARD}_warp_issue48_${STEP}" cube_1m_BACKEND --backends warp --count 1000000 --repeats 1
    same_spheres "$OUT/same_spheres_1m_${CARD}_issue48_${STEP}.txt" armadillo_1m_warp cube_1m_warp
    tar czf "$FINAL/million_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  timeline)
    gather_in timeline
    for backend in warp numba-cuda; do
      timeout 240 python3 bench/gpu_timeline.py --backend $backend --mesh /tmp/armadillo.obj --count 100000 \
        --out "$OUT/timeline_${CARD}_${backend}_issue48_${STEP}.json" 2>&1 | grep -v "^Warp\|^Module"
    done
    tar czf "$FINAL/timeline_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  launches)
    # numba-cuda's launches: the host's profile of one packing (what a launch costs in Python)
    gather_in launches
    kernels now "launches_${CARD}_numba_cuda_issue48_${STEP}" --backends numba-cuda --mesh /tmp/armadillo.obj \
      --count 100000 --repeats 1 --host-profile | grep -v "^Warp\|^Module" | head -120 \
      | tee "$OUT/launches_${CARD}_numba_cuda_issue48_${STEP}.txt"
    tar czf "$FINAL/launches_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  *) echo "usage: bash bench/gpu_issue48_step13.sh check|million|timeline|launches" >&2; exit 2 ;;
esac
