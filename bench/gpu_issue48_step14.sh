#!/usr/bin/env bash
# Issue 48, fourteenth step: the thirteenth step's candidates kept aside, each against main, in one GPU run.
# Set up on this machine first: each version's ndpack (and the replay branch's bench/launch_replay.py, the
# device-conflicts branch's tests) as .gpu2/versions/NAME.tar.xz, carried with .gpu2 (whose base/ goes: the carry
# holds 64 MiB):
#   rm -rf .gpu2/base .gpu2/versions && mkdir -p .gpu2/versions && for v in main issue48-step13-replay \
#       issue48-step14-busy-check issue48-step14-device-conflicts; do extra=; \
#     [ $v = issue48-step13-replay ] && extra="bench/launch_replay.py bench/_common.py"; \
#     [ $v = issue48-step14-device-conflicts ] && extra="tests/conftest.py tests/backends pyproject.toml"; \
#     git archive $v ndpack $extra | xz -9 > .gpu2/versions/$v.tar.xz; done
# then, after the set-up runs (../shared/device/README.md):
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step14.sh versions  the armadillo at 100,000 on Warp and numba-cuda
#        with each version's ndpack in two turns (their spheres side by side), numba-cuda's launches replayed or not
#        (bench/launch_replay.py of the replay branch), and the device store's tests of the device-conflicts branch
# The files gather in one archive under $OUT (a run brings back few files).
set -uo pipefail
source bench/gpu_header.sh
STEP=${STEP:-step14}
issue48_inputs
VERSIONS=(main issue48-step13-replay issue48-step14-busy-check issue48-step14-device-conflicts)
case "${1:-}" in
  versions)
    gather_in versions
    for version in "${VERSIONS[@]}"; do
      [ -f ".gpu2/versions/$version.tar.xz" ] || { echo "versions: .gpu2/versions/$version.tar.xz is missing" >&2; exit 2; }
      mkdir -p "/tmp/versions/$version" && xz -dc ".gpu2/versions/$version.tar.xz" | tar x -C "/tmp/versions/$version"
    done
    for turn in 1 2; do
      for version in "${VERSIONS[@]}"; do
        echo "== turn $turn, $version"
        PYTHONPATH=/tmp/versions/$version:$PYTHONPATH timeout 240 python3 bench/profile_kernels.py --stages \
          --no-profiled --backends warp numba-cuda --mesh /tmp/armadillo.obj --count 100000 --repeats 3 \
          --spheres "/tmp/armadillo_BACKEND_${version}.npz" \
          --out "$OUT/armadillo_100k_${CARD}_issue48_${STEP}_turn${turn}_${version}.json" 2>&1 \
          | grep -E "^== |now: " | grep -v "^Warp\|^Module"
      done
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
    replay=/tmp/versions/issue48-step13-replay
    PYTHONPATH=$replay:$PYTHONPATH timeout 150 python3 $replay/bench/launch_replay.py --count 5000 \
      --out "$OUT/launch_replay_${CARD}_issue48_${STEP}.json" 2>&1 | grep -v "^Warp\|^Module" | tail -6
    conflicts=/tmp/versions/issue48-step14-device-conflicts
    (cd $conflicts && PYTHONPATH=$conflicts:$PYTHONPATH timeout 150 python3 -m pytest -q -p no:cacheprovider \
      tests/backends/test_backends.py -k "conflict_check or small_device or fast_mode" 2>&1) | tail -3 \
      | tee "$OUT/gpu_tests_${CARD}_issue48_${STEP}.txt"
    tar czf "$FINAL/versions_${CARD}_issue48_${STEP}.tgz" -C $OUT .
    ;;
  *) echo "usage: bash bench/gpu_issue48_step14.sh versions" >&2; exit 2 ;;
esac
