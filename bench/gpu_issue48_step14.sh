#!/usr/bin/env bash
# Issue 48, fourteenth step: the thirteenth step's candidates kept aside, each against main, in one GPU run.
# Set up on this machine first: each version's ndpack (and the replay branch's bench/launch_replay.py, the
# device-conflicts branch's tests) as .gpu2/versions/NAME.tar.xz, carried with .gpu2 (whose base/ goes: the carry
# holds 64 MiB):
#   rm -rf .gpu2/base .gpu2/versions && mkdir -p .gpu2/versions && for v in main issue48-step13-replay \
#       issue48-step14-busy-check issue48-step14-device-conflicts issue48-step14-all; do extra=; \
#     [ $v = issue48-step13-replay ] && extra="bench/launch_replay.py bench/_common.py"; \
#     [ $v = issue48-step14-device-conflicts ] && extra="tests/conftest.py tests/backends pyproject.toml"; \
#     [ $v = issue48-step14-all ] && extra="tests/conftest.py tests/backends pyproject.toml"; \
#     git archive $v ndpack $extra | xz -9 > .gpu2/versions/$v.tar.xz; done
# then, after the set-up runs (../shared/device/README.md):
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step14.sh versions TURN  the armadillo at 100,000 on Warp and
#        numba-cuda with each version's ndpack (turn 1, then turn 2 in the next run: their spheres side by side)
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step14.sh extras  numba-cuda's launches replayed or not
#        (bench/launch_replay.py of the replay branch), the device store's tests of the device-conflicts and all
#        branches, where the device waits with all of them (bench/gpu_timeline.py), and all of them beside numba on
#        the host's cores in one process
# issue48-step14-all is main with the three branches picked on it. The files of each run gather in one archive
# under $OUT (a run brings back few files).
set -uo pipefail
source bench/gpu_header.sh
STEP=${STEP:-step14}
issue48_inputs
VERSIONS=(main issue48-step13-replay issue48-step14-busy-check issue48-step14-device-conflicts issue48-step14-all)
unpack() {
  local version=$1
  [ -f ".gpu2/versions/$version.tar.xz" ] || { echo "$version: .gpu2/versions/$version.tar.xz is missing" >&2; exit 2; }
  [ -d "/tmp/versions/$version/ndpack" ] || { mkdir -p "/tmp/versions/$version" \
    && xz -dc ".gpu2/versions/$version.tar.xz" | tar x -C "/tmp/versions/$version"; }
}
case "${1:-}" in
  versions)
    turn=${2:?versions: give the turn, 1 or 2}
    gather_in "versions_turn$turn"
    for version in "${VERSIONS[@]}"; do unpack "$version"; done
    for version in "${VERSIONS[@]}"; do
      echo "== turn $turn, $version"
      PYTHONPATH=/tmp/versions/$version:$PYTHONPATH timeout 240 python3 bench/profile_kernels.py --stages \
        --no-profiled --backends warp numba-cuda --mesh /tmp/armadillo.obj --count 100000 --repeats 3 \
        --spheres "/tmp/armadillo_BACKEND_${version}.npz" \
        --out "$OUT/armadillo_100k_${CARD}_issue48_${STEP}_turn${turn}_${version}.json" 2>&1 \
        | grep -E "^== |now: " | grep -v "^Warp\|^Module"
    done
    python3 - "${VERSIONS[@]}" <<'PY' | tee "$OUT/same_spheres_${CARD}_issue48_${STEP}.txt"
import sys
import numpy as np
for backend in ("warp", "numba-cuda"):
    main = np.load(f"/tmp/armadillo_{backend}_{sys.argv[1]}.npz")
    for version in sys.argv[2:]:
        other = np.load(f"/tmp/armadillo_{backend}_{version}.npz")
        same = len(main["radii"]) == len(other["radii"])
        change = float(np.abs(main["radii"] - other["radii"]).max()) if same else None
        print(f"{backend}, {version} against {sys.argv[1]}: spheres {len(other['radii'])} and {len(main['radii'])}, "
              f"largest radius change {change}")
PY
    tar czf "$FINAL/versions_turn${turn}_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  extras)
    gather_in extras
    for version in "${VERSIONS[@]}"; do unpack "$version"; done
    replay=/tmp/versions/issue48-step13-replay
    PYTHONPATH=$replay:$PYTHONPATH timeout 150 python3 $replay/bench/launch_replay.py --count 5000 \
      --out "$OUT/launch_replay_${CARD}_issue48_${STEP}.json" 2>&1 | grep -v "^Warp\|^Module" | tail -6
    for version in issue48-step14-device-conflicts issue48-step14-all; do
      (cd /tmp/versions/$version && PYTHONPATH=/tmp/versions/$version:$PYTHONPATH timeout 150 python3 -m pytest -q \
        -p no:cacheprovider tests/backends/test_backends.py -k "conflict_check or small_device or fast_mode" 2>&1) \
        | tail -3 | tee "$OUT/gpu_tests_${CARD}_issue48_${STEP}_${version}.txt"
    done
    all=/tmp/versions/issue48-step14-all
    for backend in warp numba-cuda; do
      PYTHONPATH=$all:$PYTHONPATH timeout 150 python3 bench/gpu_timeline.py --backend $backend \
        --mesh /tmp/armadillo.obj --count 100000 \
        --out "$OUT/timeline_${CARD}_${backend}_issue48_${STEP}_all.json" 2>&1 | grep -v "^Warp\|^Module" | tail -25
    done
    PYTHONPATH=$all:$PYTHONPATH timeout 200 python3 bench/profile_kernels.py --stages --no-profiled \
      --backends warp numba-cuda numba --mesh /tmp/armadillo.obj --count 100000 --repeats 3 \
      --out "$OUT/armadillo_100k_${CARD}_backends_issue48_${STEP}_all.json" 2>&1 | grep -E "^== |now: " \
      | grep -v "^Warp\|^Module"
    tar czf "$FINAL/extras_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  *) echo "usage: bash bench/gpu_issue48_step14.sh versions 1|2 | extras" >&2; exit 2 ;;
esac
