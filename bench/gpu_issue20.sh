#!/usr/bin/env bash
# Issue 20 (the GPU must pay) on the GPU machine, after the set-up runs (.gpu1, then .gpu2). .gpu4
# carries the 100k-triangle armadillo (armadillo.obj.xz) and the code before the issue
# (before/: ndpack and bench/profile_kernels.py of commit b7017d9), made here with
#   mkdir -p .gpu4/before && git archive b7017d9 ndpack bench/profile_kernels.py | tar -x -C .gpu4/before
#   xz -9 -c ../shared/data/meshes/armadillo.obj > .gpu4/armadillo.obj.xz && echo /.gpu4/ >> .git/info/exclude
# and carried with .gpu2 (carry: [".gpu2", ".gpu4"]). BEFORE=path compares with another version
# (the second session measured against .gpu4/before583, made alike from commit 583b665; the third
# against .gpu4/before5623, from 5623dfb; the fourth against .gpu4/before06c, from 06c4321; the ninth
# steps against .gpu4/beforef64, from f64df1c).
#   source .gpu2/setup.sh && bash bench/gpu_issue20.sh time      100,000 spheres in the armadillo,
#       before and now, Warp (cuda:0), numba-cuda and numba on the host's cores (bench/round_time.py)
#   source .gpu2/setup.sh && bash bench/gpu_issue20.sh profile   the per-round profile, before and now
#       (bench/profile_kernels.py), on both GPU backends
#   source .gpu2/setup.sh && bash bench/gpu_issue20.sh million   1,000,000 spheres in the armadillo and
#       the unit cube on Warp, before and now (bench/scale.py)
#   source .gpu2/setup.sh && bash bench/gpu_issue20.sh spread    threads per moved prototype: a launch's
#       move_ids alone (bench/step_cost.py) and whole packings with and without (bench/profile_kernels.py)
#   source .gpu2/setup.sh && bash bench/gpu_issue20.sh deallocs  numba-cuda with its frees flushed after 10
#       (numba's default) and after 1,000 pending ones (bench/round_time.py)
#   source .gpu2/setup.sh && bash bench/gpu_issue20.sh profile_fast  a cProfile of one packing per GPU backend
#       (bench/profile_fast.py): synchronisations, launches and host functions
#   source .gpu2/setup.sh && bash bench/gpu_issue20.sh tests     the GPU backends' tests
set -uo pipefail
source bench/gpu_header.sh
[ -f /tmp/armadillo.obj ] || xz -dc .gpu4/armadillo.obj.xz > /tmp/armadillo.obj
# Both versions compile the same kernel text, so they share one cache, kept between the parts.
export NDPACK_CACHE=/tmp/ndpack-gpu-cache WARP_CACHE_PATH=/tmp/ndpack-gpu-cache/warp
BEFORE=${BEFORE:-$PWD/.gpu4/before}
case "${1:-time}" in
  time)
    timeout 570 python3 bench/round_time.py --mesh /tmp/armadillo.obj --count 100000 --backends warp numba-cuda numba \
      --versions before="$BEFORE" now=. --repeats 2 --out "$OUT/round_time_h100.json" 2>&1 | grep -v "^Warp\|^Module" \
      | tee "$OUT/round_time.txt" ;;
  profile)
    PYTHONPATH=$BEFORE:${PYTHONPATH:-} timeout 280 python3 "$BEFORE/bench/profile_kernels.py" --backends warp numba-cuda \
      --mesh /tmp/armadillo.obj --count 100000 --out "$OUT/profile_before_h100.json" 2>&1 | grep -v "^Warp\|^Module" \
      | tee "$OUT/profile_before.txt"
    timeout 280 python3 bench/profile_kernels.py --backends warp numba-cuda --mesh /tmp/armadillo.obj --count 100000 \
      --out "$OUT/profile_now_h100.json" 2>&1 | grep -v "^Warp\|^Module" | tee "$OUT/profile_now.txt" ;;
  million)
    for version in before now; do
      path=$PWD; [ $version = before ] && path=$BEFORE
      PYTHONPATH=$path:${PYTHONPATH:-} python3 -c "import ndpack; print(\"$version:\", ndpack.__file__)"
      PYTHONPATH=$path:${PYTHONPATH:-} timeout 280 python3 bench/scale.py --cases armadillo cube --backends warp \
        --mesh /tmp/armadillo.obj --counts 1000000 --faithful-count 0 --box-count 1000000 \
        --out "$OUT/scale_million_h100_warp_$version.json" 2>&1 | grep -v "^Warp\|^Module" | tee "$OUT/million_$version.txt"
    done ;;
  spread)  # the seventh steps: threads per moved prototype (step_cost's spread rows, profile_kernels' spread-1)
    timeout 250 python3 bench/step_cost.py --backends warp numba-cuda --mesh /tmp/armadillo.obj --count 100000 \
      --out "$OUT/step_cost_spread_h100.json" 2>&1 | grep -v "^Warp\|^Module" | tee "$OUT/step_cost_spread.txt"
    timeout 300 python3 bench/profile_kernels.py --backends warp numba-cuda --mesh /tmp/armadillo.obj --count 100000 \
      --variants now spread-1 threads-2^15 threads-2^16 threads-2^18 threads-2^19 --repeats 2 \
      --out "$OUT/profile_spread_h100.json" 2>&1 | grep -v "^Warp\|^Module" \
      | tee "$OUT/profile_spread.txt" ;;
  deallocs)  # the eighth steps: numba-cuda's deferred frees (each flush synchronises the device)
    for count in 10 1000; do
      NUMBA_CUDA_MAX_PENDING_DEALLOCS_COUNT=$count timeout 250 python3 bench/round_time.py --mesh /tmp/armadillo.obj \
        --count 100000 --backends numba-cuda --versions now=. --repeats 3 --out "$OUT/round_time_deallocs_$count.json" \
        2>&1 | grep -v "^Warp\|^Module" | tee "$OUT/round_time_deallocs_$count.txt"
    done ;;
  profile_fast)  # the eighth and ninth steps: where the host's time goes, a cProfile of one packing
    timeout 280 python3 bench/profile_fast.py --backends warp numba-cuda --mesh /tmp/armadillo.obj --count 100000 \
      --sort tottime cumulative --top 45 2>&1 | grep -v "^Warp\|^Module" | tee "$OUT/profile_fast.txt" ;;
  tests)
    timeout 570 python3 -m pytest -q -p no:cacheprovider tests/backends/test_backends.py tests/test_scale.py tests/test_protosphere.py \
      -k "numba-cuda or warp or cuda or fast" 2>&1 | tail -15 | tee "$OUT/tests.txt" ;;
  *) echo "unknown part $1: time, profile, million, spread, deallocs, profile_fast or tests" >&2; exit 2 ;;
esac
