"""Warp's sphere-index kernels with the walk's guard as written and as it was, kernel by kernel.

    python bench/index_guard.py {flag,return,none} --backends warp --mesh armadillo.obj --count 100000 --repeats 1

Runs ``bench/profile_kernels.py`` (every launch timed on the device) with the Warp module's text
changed: ``flag`` is the code as it is (a corrupt list sets a flag and breaks out, and the query
returns NaN after its loops: ``ndpack/backends/index_kernels.py``), ``return`` the guard as it was
written before (a return inside the loops), ``none`` no guard. On an H100 the return made
``index_fill_ids`` and ``index_bound_ids`` 3x slower than no guard, the flag as fast as none
(``bash bench/gpu_issue48_step10.sh guard``).
"""

import runpy
import sys
from pathlib import Path

import ndpack.backends.warp_backend as warp_backend

FLAG = ("            if s >= radii.shape[0] or s >= nxt.shape[0] or s >= level_next.shape[0]:\n"
        "                corrupt = int(1)\n                break\n")
RETURN = ("            if s >= radii.shape[0] or s >= nxt.shape[0] or s >= level_next.shape[0]:\n"
          "                return (F(wp.nan), found)\n")


def main():
    variant = sys.argv.pop(1)
    if variant not in ("flag", "return", "none"):
        raise SystemExit("usage: python bench/index_guard.py {flag,return,none} PROFILE_KERNELS_ARGS...")
    if FLAG not in warp_backend.KERNELS:
        raise SystemExit("the guard is not where this script expects it (ndpack/backends/index_kernels.py)")
    warp_backend.KERNELS = warp_backend.KERNELS.replace(FLAG, {"flag": FLAG, "return": RETURN, "none": ""}[variant])
    script = Path(__file__).with_name("profile_kernels.py")
    sys.argv[0] = str(script)
    runpy.run_path(str(script), run_name="__main__")


if __name__ == "__main__":
    main()
