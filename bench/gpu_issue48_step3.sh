#!/usr/bin/env bash
# Issue 48, third step (cooperative walks in the moves, ndpack.backends.warp_lanes; code 5d70ad2), on
# the GPU machine after the set-up runs (../shared/device/README.md): bench/gpu_issue48_step4.sh with
# this step's file names and variants:
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step3.sh lanes     a fresh machine's first packing of
#        the armadillo; then the armadillo at 100,000: cooperative walks in move launches of at most 4,096
#        prototypes (now) against never (lanes-off) and at most 1,024, 8,192 and 16,384; every launch timed
#        in a second run; numba on the host's cores beside them
#   source .gpu2/setup.sh && bash bench/gpu_issue48_step3.sh million   the armadillo at 1,000,000, now and
#        lanes-off (2 runs each)
STEP=step3 VARIANTS="now lanes-off lanes-1024 lanes-8192 lanes-16384" exec bash bench/gpu_issue48_step4.sh "$@"
