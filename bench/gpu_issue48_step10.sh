#!/usr/bin/env bash
# Issue 48, tenth step (one description for both GPU backends: the move, the sphere index's queries and the
# prototype store's kernels written once, printed for Numba, numba-cuda and Warp by ndpack/kernels/portable.py),
# on the GPU machine after the set-up runs (../shared/device/README.md), with numpy 2.4 carried:
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step10.sh tests  the printer's, the device stores' and the
#        cooperative walks' tests on the device (both GPU backends)
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step10.sh turns  the armadillo at 100,000 on Warp and on
#        numba-cuda with this checkout and .gpu2/base (BASE, the commit before the step: git archive BASE ndpack |
#        tar x -C .gpu2/base) in turns (2 runs each), their spheres side by side; then numba-cuda, Warp and numba
#        on the host's cores in one process (3 runs each)
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step10.sh fresh  a fresh machine's first packing of the
#        armadillo, every cache empty (bench/fresh_machine.py): numba-cuda and Warp, this checkout and .gpu2/base;
#        then Warp alone in 3 turns (3 runs each), and Warp's spheres beside numba-cuda's (both this checkout)
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step10.sh profile  Warp's kernels one by one (every launch
#        timed on the device, bench/profile_kernels.py), .gpu2/base and this checkout in turns
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step10.sh guard  Warp's index kernels with the walk's guard as
#        written (a flag), as it was (a return inside the loops) and without (bench/index_guard.py), in turns; then
#        numba-cuda's with the flag
# The files gather in one archive under $OUT (a run brings back few files).
set -uo pipefail
source bench/gpu_header.sh
STEP=${STEP:-step10}  # another name for a second run of the same step
issue48_inputs
case "${1:-}" in
  tests)
    timeout 400 python3 -m pytest -q -p no:cacheprovider tests/kernels/test_portable.py \
      tests/backends/test_numba_cuda_lanes.py tests/backends/test_warp_lanes.py tests/backends/test_backends.py \
      -k "portable or numba-cuda or warp or device or lanes" 2>&1 | tail -8 | tee "$OUT/gpu_tests_${CARD}_issue48_${STEP}.txt"
    ;;
  turns)
    need_base turns
    gather_in turns
    for backend in warp numba-cuda; do
      for turn in 1 2; do
        for version in base now; do
          kernels "$version" "armadillo_100k_${CARD}_${backend/-/_}_issue48_${STEP}_turn${turn}" --backends "$backend" \
            --mesh /tmp/armadillo.obj --count 100000 --repeats 2 --spheres "/tmp/${backend}_${version}.npz"
        done
      done
    done
    for backend in warp numba-cuda; do
      for version in base now; do cp "/tmp/${backend}_${version}.npz" "/tmp/armadillo_${backend}_${version}.npz"; done
    done
    same_spheres "$OUT/same_spheres_${CARD}_issue48_${STEP}.txt" armadillo_warp armadillo_numba-cuda
    kernels now "armadillo_100k_${CARD}_backends_issue48_${STEP}" --backends numba-cuda warp numba \
      --mesh /tmp/armadillo.obj --count 100000 --repeats 3
    tar czf "$FINAL/turns_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  fresh)
    need_base fresh
    gather_in fresh
    fresh_runs "fresh_machine_${CARD}_issue48_${STEP}" 280 numba-cuda warp
    for turn in 1 2 3; do
      for version in base now; do
        kernels "$version" "armadillo_100k_${CARD}_warp_issue48_${STEP}_warp_turn${turn}" --backends warp \
          --mesh /tmp/armadillo.obj --count 100000 --repeats 3 --spheres "/tmp/armadillo_warp_${version}.npz"
      done
    done
    kernels now "armadillo_100k_${CARD}_numba_cuda_issue48_${STEP}_cuda" --backends numba-cuda \
      --mesh /tmp/armadillo.obj --count 100000 --repeats 1 --spheres /tmp/armadillo_cuda_now.npz
    cp /tmp/armadillo_warp_now.npz /tmp/warp_against_cuda_base.npz && cp /tmp/armadillo_cuda_now.npz /tmp/warp_against_cuda_now.npz
    same_spheres "$OUT/same_spheres_${CARD}_issue48_${STEP}_warp.txt" armadillo_warp warp_against_cuda
    tar czf "$FINAL/fresh_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  profile)
    need_base profile
    gather_in profile
    for turn in 1 2; do
      for version in base now; do
        path=$PYTHONPATH
        [ "$version" = base ] && path=$PWD/.gpu2/base:$PYTHONPATH
        PYTHONPATH=$path timeout 200 python3 bench/profile_kernels.py --backends ${BACKEND:-warp} --mesh /tmp/armadillo.obj \
          --count 100000 --repeats 1 --out "$OUT/profile_${CARD}_issue48_${STEP}_turn${turn}_${version}.json" 2>&1 \
          | grep -v "^Warp\|^Module\|^ndpack: compiling" | head -32
      done
    done
    tar czf "$FINAL/profile_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  guard)
    for variant in return none flag return none flag; do
      echo "## warp, guard: $variant"
      python3 bench/index_guard.py "$variant" --backends warp --mesh /tmp/armadillo.obj --count 100000 --repeats 1 \
        2>&1 | grep -E "== |index_fill|index_bound|touched_index|device kernels"
    done | tee "$OUT/index_guard_${CARD}_issue48_${STEP}.txt"
    echo "## numba-cuda, guard: flag" | tee -a "$OUT/index_guard_${CARD}_issue48_${STEP}.txt"
    python3 bench/index_guard.py flag --backends numba-cuda --mesh /tmp/armadillo.obj --count 100000 --repeats 1 2>&1 \
      | grep -E "== |index_fill|index_bound|touched_index|device kernels" | tee -a "$OUT/index_guard_${CARD}_issue48_${STEP}.txt"
    ;;
  *) echo "usage: bash bench/gpu_issue48_step10.sh tests|turns|fresh|profile|guard" >&2; exit 2 ;;
esac
