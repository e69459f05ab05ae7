#!/usr/bin/env bash
# Issue 48, sixth step (a move launch's chain: the polish ahead runs the polish schedule's tail,
# rounds.AHEAD_EPS_START; the split's two signed distances on a thread each, split_cut and
# cell_distances), on the GPU machine after the set-up runs (../shared/device/README.md):
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step6.sh measure  this checkout against the one in
#        .gpu2/base (BASE, the commit before the step: git archive BASE ndpack | tar x -C .gpu2/base), in one
#        run: a fresh machine's first packing of a mesh; the armadillo at 100,000 (3 runs each, and this
#        checkout with the whole polish schedule ahead, variant ahead-whole; numba on the host's cores beside
#        them), at 1,000,000 (2 runs each), the unit cube at 1,000,000 (2 runs each) and the unit square at
#        1,000,000 (2 runs); the spheres side by side; the files in one archive, $OUT/measure_CARD_issue48_step6.tgz
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step6.sh numba    numba on the host's cores: the unit cube
#        and square at 1,000,000 (one run each), for the ratios beside the measure's Warp figures
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step6.sh split    finer cells on a GPU (rounds.SPLIT_RATIO_AHEAD,
#        profile_kernels' split-R variants) in one process each: the armadillo at 100,000 (3 runs of 4, 3 and 2.5)
#        and at 1,000,000 (2 runs of 4 and 3), the unit cube at 1,000,000 (2 runs of 4 and 3)
#   source .gpu2/setup.sh && STEP=step6d bash bench/gpu_issue48_step6.sh turns  the armadillo at 100,000 with
#        .gpu2/base's ndpack and this checkout's in turn, twice (5 runs each), then numba on the host's cores
#        (3 runs) and this checkout again (5 runs, pass3): a difference smaller than one lease's drift
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step6.sh profile  the armadillo at 100,000 with every launch
#        timed (and 3 unprofiled runs, stages timed): what bench/work_model.py --against sets its counts beside
set -uo pipefail
source bench/gpu_header.sh
STEP=${STEP:-step6}  # another name for a second run of the same step
issue48_inputs
case "${1:-}" in
  measure)
    need_base measure
    gather_in measure
    cold_first_packing "$OUT/compile_${CARD}_issue48_${STEP}.txt"
    kernels base "armadillo_100k_${CARD}_issue48_${STEP}" --backends warp --mesh /tmp/armadillo.obj \
      --count 100000 --repeats 3 --spheres /tmp/armadillo_100k_base.npz
    kernels now "armadillo_100k_${CARD}_issue48_${STEP}" --backends warp --mesh /tmp/armadillo.obj \
      --count 100000 --repeats 3 --variants now ahead-whole --spheres /tmp/armadillo_100k_now.npz
    kernels now "armadillo_100k_${CARD}host_numba_issue48_${STEP}" --backends numba --mesh /tmp/armadillo.obj \
      --count 100000 --repeats 3
    for version in base now; do
      kernels $version "armadillo_1m_${CARD}_issue48_${STEP}" --backends warp --mesh /tmp/armadillo.obj \
        --count 1000000 --repeats 2 --spheres /tmp/armadillo_1m_$version.npz
      kernels $version "cube_1m_${CARD}_issue48_${STEP}" --backends warp --count 1000000 --repeats 2 \
        --spheres /tmp/cube_1m_$version.npz
    done
    kernels now "square_1m_${CARD}_issue48_${STEP}" --backends warp --square --count 1000000 --repeats 2
    same_spheres "$OUT/same_spheres_${CARD}_issue48_${STEP}.txt" armadillo_100k armadillo_1m cube_1m
    tar czf "$FINAL/measure_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  numba)
    kernels now "cube_1m_${CARD}host_numba_issue48_${STEP}" --backends numba --count 1000000 --repeats 1
    kernels now "square_1m_${CARD}host_numba_issue48_${STEP}" --backends numba --square --count 1000000 --repeats 1
    ;;
  split)
    kernels now "split_armadillo_100k_${CARD}_issue48_${STEP}" --backends warp --mesh /tmp/armadillo.obj \
      --count 100000 --repeats 3 --variants now split-3 split-2.5
    kernels now "split_armadillo_1m_${CARD}_issue48_${STEP}" --backends warp --mesh /tmp/armadillo.obj \
      --count 1000000 --repeats 2 --variants now split-3
    kernels now "split_cube_1m_${CARD}_issue48_${STEP}" --backends warp --count 1000000 --repeats 2 \
      --variants now split-3
    ;;
  turns)
    turns "armadillo_100k_${CARD}_issue48_${STEP}" 2
    kernels now "armadillo_100k_${CARD}host_numba_issue48_${STEP}" --backends numba --mesh /tmp/armadillo.obj \
      --count 100000 --repeats 3
    kernels now "armadillo_100k_${CARD}_issue48_${STEP}_pass3" --backends warp --mesh /tmp/armadillo.obj \
      --count 100000 --repeats 5
    ;;
  profile)
    timeout 300 python3 bench/profile_kernels.py --backends warp --mesh /tmp/armadillo.obj --count 100000 \
      --repeats 3 --stages --out "$OUT/profile_kernels_${CARD}_armadillo_issue48_${STEP}.json" 2>&1 \
      | grep -v "^Warp\|^Module\|^ndpack: compiling" | tail -30
    ;;
  *) echo "usage: bash bench/gpu_issue48_step6.sh measure|numba|split|turns|profile" >&2; exit 2 ;;
esac
