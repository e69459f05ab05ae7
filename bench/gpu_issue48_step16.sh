#!/usr/bin/env bash
# Issue 48, sixteenth step, on the GPU machine after the set-up runs (../shared/device/README.md):
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step16.sh inline  Warp with .gpu2/base's ndpack
#        (git archive BASE ndpack | tar x -C .gpu2/base) and this checkout's in turns: the armadillo at 100,000
#        (two turns, medians of 3), the unit cube and the unit square at a million (one turn, medians of 2),
#        numba-cuda beside .gpu2/base at a million, and the spheres of each side by side
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step16.sh million  numba on the host's cores at a million in
#        the cube and the square (one run each), Warp's peak GPU memory at a million (the armadillo, the cube),
#        and a fresh machine's first packing of the armadillo on Warp and numba-cuda (bench/fresh_machine.py)
# The files gather in one archive under $OUT (a run brings back few files).
set -uo pipefail
source bench/gpu_header.sh
STEP=${STEP:-step16}
issue48_inputs
case "${1:-}" in
  inline)
    need_base inline
    gather_in inline
    in_turns "armadillo_100k_${CARD}_warp_issue48_${STEP}" armadillo_warp --backends warp --mesh /tmp/armadillo.obj \
      --count 100000 --repeats 3
    for version in base now; do
      backends=warp
      [ $version = base ] && backends="warp numba-cuda"
      kernels $version "cube_1m_${CARD}_backends_issue48_${STEP}" --backends $backends --count 1000000 --repeats 2 \
        --spheres "/tmp/cube_BACKEND_${version}.npz" | grep -E "^== |now: "
      kernels $version "square_1m_${CARD}_backends_issue48_${STEP}" --backends $backends --square --count 1000000 \
        --repeats 2 --spheres "/tmp/square_BACKEND_${version}.npz" | grep -E "^== |now: "
    done
    same_spheres "$OUT/same_spheres_${CARD}_issue48_${STEP}.txt" armadillo_warp cube_warp square_warp
    tar czf "$FINAL/inline_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  million)
    gather_in million
    kernels now "cube_1m_${CARD}_numba_issue48_${STEP}" --backends numba --count 1000000 --repeats 1 \
      | grep -E "^== |now: "
    kernels now "square_1m_${CARD}_numba_issue48_${STEP}" --backends numba --square --count 1000000 --repeats 1 \
      | grep -E "^== |now: "
    STEP=$STEP bash bench/gpu_issue48_step5.sh memory
    timeout 240 python3 bench/fresh_machine.py --mesh /tmp/armadillo.obj --backends warp numba-cuda \
      --out "$OUT/fresh_machine_${CARD}_issue48_${STEP}.json" 2>&1 | grep -v "^Warp\|^Module"
    tar czf "$FINAL/million_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  *) echo "usage: bash bench/gpu_issue48_step16.sh inline|million" >&2; exit 2 ;;
esac
