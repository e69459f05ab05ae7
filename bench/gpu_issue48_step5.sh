#!/usr/bin/env bash
# Issue 48, fifth step (the host's part of a round: the sphere index built on the device, partial
# sorts, the conflict check's pairs), on the GPU machine after the set-up runs (../shared/device/README.md):
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step5.sh host     where the host's time goes: cProfile of
#        the armadillo at 100,000 and 1,000,000 and the unit cube at 1,000,000 on Warp (fast mode)
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step5.sh measure  this checkout against the one in
#        .gpu2/base (BASE, the commit before the step: git archive BASE ndpack | tar x -C .gpu2/base), in one
#        run: the armadillo at 100,000 (3 runs each; numba on the host's cores beside them) and at
#        1,000,000 (2 runs each; and without polishing ahead), the unit cube at 1,000,000 (2 runs each) and
#        the unit square at 1,000,000 (2 runs); the spheres of both side by side; the files in one
#        archive, $OUT/measure_CARD_issue48_STEP.tgz
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step5.sh final    this checkout alone: a fresh machine's
#        first packing of a mesh; the armadillo at 100,000 (3 runs; numba on the host's cores beside it)
#        and 1,000,000 (2 runs), the unit cube and square at 1,000,000 (2 runs; numba one run each), and the
#        host's cProfile of the armadillo at 1,000,000; the files in one archive, $OUT/final_CARD_issue48_step5.tgz
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step5.sh profile  the armadillo at 100,000 with every launch
#        timed (and 3 unprofiled runs, stages timed): what bench/work_model.py --against sets its counts beside
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step5.sh memory   the GPU's peak memory (nvidia-smi, every
#        0.2 s, the CUDA context included) in one packing of the armadillo and of the unit cube at 1,000,000
#        (BACKEND=numba-cuda: on that backend; Warp by default)
set -uo pipefail
source bench/gpu_header.sh
STEP=${STEP:-step5}
issue48_inputs
case "${1:-}" in
  host)
    for count in 100000 1000000; do
      timeout 200 python3 bench/profile_rounds.py --backends warp --mode fast --mesh /tmp/armadillo.obj \
        --count $count --top 30 --out "$OUT/host_${CARD}_armadillo_${count}_issue48_${STEP}.txt" 2>&1 \
        | grep -v "^Warp\|^Module"
    done
    timeout 150 python3 bench/profile_rounds.py --backends warp --mode fast --count 1000000 --top 30 \
      --out "$OUT/host_${CARD}_cube_1000000_issue48_${STEP}.txt" 2>&1 | grep -v "^Warp\|^Module"
    ;;
  measure)
    need_base measure
    gather_in measure
    for version in base now; do
      kernels $version "armadillo_100k_${CARD}_issue48_${STEP}" --backends warp --mesh /tmp/armadillo.obj \
        --count 100000 --repeats 3 --spheres /tmp/armadillo_100k_$version.npz
    done
    kernels now "armadillo_100k_${CARD}host_numba_issue48_${STEP}" --backends numba --mesh /tmp/armadillo.obj \
      --count 100000 --repeats 3
    kernels base "armadillo_1m_${CARD}_issue48_${STEP}" --backends warp --mesh /tmp/armadillo.obj --count 1000000 \
      --repeats 2 --spheres /tmp/armadillo_1m_base.npz
    kernels now "armadillo_1m_${CARD}_issue48_${STEP}" --backends warp --mesh /tmp/armadillo.obj --count 1000000 \
      --repeats 2 --variants now no-ahead --spheres /tmp/armadillo_1m_now.npz
    for version in base now; do
      kernels $version "cube_1m_${CARD}_issue48_${STEP}" --backends warp --count 1000000 --repeats 2 \
        --spheres /tmp/cube_1m_$version.npz
    done
    kernels now "square_1m_${CARD}_issue48_${STEP}" --backends warp --square --count 1000000 --repeats 2
    same_spheres "$OUT/same_spheres_${CARD}_issue48_${STEP}.txt" armadillo_100k armadillo_1m cube_1m
    tar czf "$FINAL/measure_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  final)
    gather_in final
    cold_first_packing "$OUT/compile_${CARD}_issue48_${STEP}.txt"
    kernels now "armadillo_100k_${CARD}_issue48_${STEP}" --backends warp --mesh /tmp/armadillo.obj --count 100000 \
      --repeats 3
    kernels now "armadillo_100k_${CARD}host_numba_issue48_${STEP}" --backends numba --mesh /tmp/armadillo.obj \
      --count 100000 --repeats 3
    kernels now "armadillo_1m_${CARD}_issue48_${STEP}" --backends warp --mesh /tmp/armadillo.obj --count 1000000 \
      --repeats 2
    kernels now "cube_1m_${CARD}_issue48_${STEP}" --backends warp --count 1000000 --repeats 2
    kernels now "square_1m_${CARD}_issue48_${STEP}" --backends warp --square --count 1000000 --repeats 2
    kernels now "cube_1m_${CARD}host_numba_issue48_${STEP}" --backends numba --count 1000000 --repeats 1
    kernels now "square_1m_${CARD}host_numba_issue48_${STEP}" --backends numba --square --count 1000000 --repeats 1
    timeout 200 python3 bench/profile_rounds.py --backends warp --mode fast --mesh /tmp/armadillo.obj \
      --count 1000000 --top 30 --out "$OUT/host_${CARD}_armadillo_1000000_issue48_${STEP}.txt" 2>&1 | tail -3
    tar czf "$FINAL/final_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  profile)
    timeout 300 python3 bench/profile_kernels.py --backends warp --mesh /tmp/armadillo.obj --count 100000 \
      --repeats 3 --stages --out "$OUT/profile_kernels_${CARD}_armadillo_issue48_${STEP}.json" 2>&1 \
      | grep -v "^Warp\|^Module\|^ndpack: compiling" | tail -30
    ;;
  memory)
    for case in armadillo cube; do
      shape="nd.TriangleMesh.load('/tmp/armadillo.obj')"
      [ $case = cube ] && shape="nd.Box(np.zeros(3), np.ones(3))"
      python3 -c "import ndpack as nd, numpy as np; nd.pack($shape, 3, backend='${BACKEND:-warp}', mode='fast')" 2>&1 | tail -1
      nvidia-smi --query-gpu=memory.used --format=csv,noheader,nounits -lms 200 > /tmp/memory_$case.txt &
      sampler=$!
      python3 -c "
import time, ndpack as nd, numpy as np
started = time.perf_counter()
packing = nd.pack($shape, 1_000_000, backend='${BACKEND:-warp}', mode='fast', progress=False)
print('$case', len(packing.radii), 'spheres', f'{time.perf_counter() - started:.2f} s', f'fill {packing.fill:.5f}')
" 2>&1 | grep -v "^Warp\|^Module"
      kill $sampler
      echo "$case at 1,000,000: peak GPU memory used (MiB, whole device): $(sort -n /tmp/memory_$case.txt | tail -1)" \
        | tee -a "$OUT/memory_${CARD}_issue48_${STEP}.txt"
    done
    ;;
  *) echo "usage: bash bench/gpu_issue48_step5.sh host|measure|final|profile|memory" >&2; exit 2 ;;
esac
