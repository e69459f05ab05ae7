#!/usr/bin/env bash
# Issue 48, eleventh step, on the GPU machine after the set-up runs (../shared/device/README.md), with numpy 2.4
# carried:
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step11.sh where  where the armadillo at 100,000 spends its
#        time now: every kernel timed (bench/profile_kernels.py), the stages of unprofiled runs and the host's
#        cProfile, on Warp and numba-cuda, then numba on the host's cores in the same process
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step11.sh levels  Warp's CUDA optimisation levels 2 (ndpack's)
#        and 3 (Warp's default) against a fresh first packing and 100,000 spheres (bench/compile_options.py)
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step11.sh deallocs  numba-cuda on the armadillo at 100,000 with
#        its deallocations freed in batches of 11 (numba-cuda's default) and never (a batch's cuMemFree waits for
#        the device), in turns
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step11.sh flush  numba-cuda, this checkout (the store frees
#        where its stream is idle) against .gpu2/base in turns, their spheres side by side; then numba-cuda, Warp
#        and numba on the host's cores in one process; the device store's tests
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step11.sh million  a million spheres in the armadillo, the cube
#        and the square on Warp and numba-cuda (medians of 2), and Warp's peak GPU memory for the armadillo and the
#        cube (bench/gpu_issue48_step5.sh memory)
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step11.sh level-turns  Warp at levels 2 and 3 in turns, every
#        launch timed (bench/profile_kernels.py --warp-level)
#   Warp's level 3 built in a background process while a first packing runs at 2: kept aside at 1fbb251 (not on
#        main), with its modes tiers and turns in that commit's copy of this script (the turns: level-turns here).
# The files gather in one archive under $OUT (a run brings back few files).
set -uo pipefail
source bench/gpu_header.sh
STEP=${STEP:-step11}  # another name for a second run of the same step
issue48_inputs
case "${1:-}" in
  where)
    gather_in where
    for backend in warp numba-cuda; do
      timeout 240 python3 bench/profile_kernels.py --backends "$backend" --mesh /tmp/armadillo.obj --count 100000 \
        --repeats 3 --stages --host-profile --out "$OUT/where_${CARD}_${backend/-/_}_issue48_${STEP}.json" 2>&1 \
        | grep -v "^Warp\|^Module\|^ndpack: compiling" | tee "$OUT/where_${CARD}_${backend/-/_}_issue48_${STEP}.txt" | head -90
    done
    kernels now "armadillo_100k_${CARD}_backends_issue48_${STEP}" --backends numba-cuda warp numba \
      --mesh /tmp/armadillo.obj --count 100000 --repeats 3
    tar czf "$FINAL/where_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  levels)
    timeout 560 python3 bench/compile_options.py --mesh /tmp/armadillo.obj --variants ndpack O3 ndpack O3 --count 100000 \
      --repeats 3 --out "$OUT/compile_options_${CARD}_issue48_${STEP}.json" 2>&1 | grep -v "^Warp\|^Module" | tail -30
    ;;
  level-turns)
    # Warp at ndpack's level and at 3 in turns, every launch timed once, then 3 runs unprofiled (what 1fbb251's
    # turns measured with its background build).
    gather_in level-turns
    for turn in 1 2; do
      for level in 2 3; do
        timeout 200 python3 bench/profile_kernels.py --backends warp --mesh /tmp/armadillo.obj --count 100000 \
          --repeats 3 --stages --warp-level $level --spheres "/tmp/armadillo_warp_level$level.npz" \
          --out "$OUT/armadillo_100k_${CARD}_warp_level${level}_issue48_${STEP}_turn${turn}.json" 2>&1 \
          | grep -E "^== |move_ids|cell_distances|device kernels|now: "
      done
    done
    tar czf "$FINAL/level_turns_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  deallocs)
    gather_in deallocs
    for turn in 1 2; do
      for count in 10 1000000; do
        NUMBA_CUDA_MAX_PENDING_DEALLOCS_COUNT=$count NUMBA_CUDA_MAX_PENDING_DEALLOCS_RATIO=0.9 \
          kernels now "armadillo_100k_${CARD}_numba_cuda_deallocs${count}_issue48_${STEP}_turn${turn}" \
          --backends numba-cuda --mesh /tmp/armadillo.obj --count 100000 --repeats 3 | grep -E "^== |now: "
      done
    done
    tar czf "$FINAL/deallocs_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  flush)
    need_base flush
    gather_in flush
    in_turns "armadillo_100k_${CARD}_numba_cuda_issue48_${STEP}" armadillo_numba-cuda --backends numba-cuda \
      --mesh /tmp/armadillo.obj --count 100000 --repeats 3
    same_spheres "$OUT/same_spheres_${CARD}_issue48_${STEP}.txt" armadillo_numba-cuda
    beside_and_store_tests "armadillo_100k_${CARD}_backends_issue48_${STEP}"
    tar czf "$FINAL/flush_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  million)
    gather_in million
    kernels now "armadillo_1m_${CARD}_backends_issue48_${STEP}" --backends warp numba-cuda --mesh /tmp/armadillo.obj \
      --count 1000000 --repeats 2 | grep -E "^== |now: "
    kernels now "cube_1m_${CARD}_backends_issue48_${STEP}" --backends warp numba-cuda --count 1000000 --repeats 2 \
      | grep -E "^== |now: "
    kernels now "square_1m_${CARD}_backends_issue48_${STEP}" --backends warp numba-cuda --square --count 1000000 \
      --repeats 2 | grep -E "^== |now: "
    STEP=$STEP bash bench/gpu_issue48_step5.sh memory
    tar czf "$FINAL/million_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  *) echo "usage: bash bench/gpu_issue48_step11.sh where|levels|level-turns|deallocs|flush|million" >&2; exit 2 ;;
esac
