#!/usr/bin/env bash
# Issue 47 on the GPU machine, after the set-up runs (../shared/device/README.md):
#   source .gpu2/setup.sh && bash bench/gpu_issue47.sh device   the device index's tests on CUDA, then the
#                                                                4-D and 5-D ball with a hole at 100,000 on Warp
#   source .gpu2/setup.sh && bash bench/gpu_issue47.sh window   the same on Warp at two earlier commits
#   source .gpu2/setup.sh && bash bench/gpu_issue47.sh host     the same on numba on the host's cores, and
#                                                                default threads against one (bench/threads.py)
# numba-cuda is left out: the staged image's numpy 2.5 lacks np.row_stack, which it needs.
set -uo pipefail
source bench/gpu_header.sh
export NDPACK_CACHE=/tmp/ndpack-gpu-cache WARP_CACHE_PATH=/tmp/ndpack-gpu-cache/warp
case "${1:-device}" in
  device)
    timeout 240 python3 -m pytest -q -x -p no:cacheprovider tests/test_scale.py -k "device and not numba" 2>&1 | tail -3 \
      | tee "$OUT/tests_device.txt"
    timeout 330 python3 bench/index_speed.py --cases 4d 5d --repeats 1 --backend warp \
      --out "$OUT/index_speed_h100_warp_issue47.json" 2>&1 | grep -v "^Warp\|^Module" | tail -4
    ;;
  window)  # the fast window's and the index's cost on the GPU: folders _v_f1ab864 and _v_f7731f1 hold those
           # commits' ndpack (git archive REV ndpack | tar x -C _v_REV), made here before the run
    timeout 560 python3 bench/index_speed.py --cases 4d 5d --repeats 1 --backend warp --mode fast \
      --before _v_f1ab864 _v_f7731f1 --out "$OUT/index_speed_h100_warp_versions_issue47.json" 2>&1 \
      | grep -v "^Warp\|^Module" | grep "run 1"
    ;;
  host)
    timeout 200 python3 bench/index_speed.py --cases 4d 5d --repeats 1 --backend numba \
      --out "$OUT/index_speed_h100host_numba_issue47.json" 2>&1 | tail -4
    timeout 380 python3 bench/threads.py --repeats 3 --out "$OUT/threads_h100host_issue47.json" 2>&1 | tail -12
    ;;
esac
