#!/usr/bin/env bash
# Issue 48, twelfth step, on the GPU machine after the set-up runs (../shared/device/README.md), with numpy 2.4
# carried:
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step12.sh fresh  a fresh machine's first packing of the armadillo
#        (bench/fresh_machine.py: every cache empty) on numba-cuda and Warp, this checkout (compile helpers:
#        ndpack.compile_ahead) against .gpu2/base in two turns
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step12.sh check  numba-cuda's spheres at 100,000 against .gpu2/base's
#        (the window's kernels now take a float64 bound), the armadillo at 100,000 on numba-cuda, Warp and numba on the
#        host's cores in one process, and the device store's tests
# The files gather in one archive under $OUT (a run brings back few files).
set -uo pipefail
source bench/gpu_header.sh
STEP=${STEP:-step12}
issue48_inputs
case "${1:-}" in
  fresh)
    need_base fresh
    gather_in fresh
    for turn in 1 2; do
      fresh_runs "fresh_machine_${CARD}_issue48_${STEP}_turn${turn}" 200 numba-cuda warp
    done
    tar czf "$FINAL/fresh_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  check)
    need_base check
    gather_in check
    for version in base now; do
      kernels "$version" "armadillo_100k_${CARD}_numba_cuda_issue48_${STEP}" --backends numba-cuda \
        --mesh /tmp/armadillo.obj --count 100000 --repeats 2 --spheres "/tmp/armadillo_numba-cuda_${version}.npz" \
        | grep -E "^== |now: "
    done
    same_spheres "$OUT/same_spheres_${CARD}_issue48_${STEP}.txt" armadillo_numba-cuda
    beside_and_store_tests "armadillo_100k_${CARD}_backends_issue48_${STEP}"
    tar czf "$FINAL/check_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  *) echo "usage: bash bench/gpu_issue48_step12.sh fresh|check" >&2; exit 2 ;;
esac
