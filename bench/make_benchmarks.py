"""Write docs/benchmarks.md: today's figures, one table per kind, from the results in bench/results.

    python bench/make_benchmarks.py                 # writes docs/benchmarks.md
    python bench/make_benchmarks.py --out -         # prints it instead

Every figure on the page is read from a results file here; none is typed in. Each table names the
command that reproduces it, the machine and versions, the commit whose code it measured and its
results file. The steps that led to these figures, with those of older code, stay in
docs/benchmarks-history.md, written by hand. tests/test_figures.py checks that the page is what
this script writes now, so a new results file reaches the page by a line in ``SOURCES`` and a run.

The script reads JSON only (no ndpack import): it runs anywhere, whatever the package's layout.
"""

from __future__ import annotations

import argparse
import json
import re
import statistics
import sys
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "bench" / "results"
PAGE = ROOT / "docs" / "benchmarks.md"
#: A cell that starts with a number (not "2-D ..."): its column aligns right.
NUMBER = re.compile(r"(> )?\d[\d.,]*(\s|$|%|\*)")


@dataclass(frozen=True)
class Machine:
    hardware: str
    python: str
    numpy: str
    libraries: str  # as the runs' logs give them (most results files record only Python and NumPy)


MACHINES = {
    "2 cores": Machine("AMD EPYC (as `/proc/cpuinfo` names it), 2 cores shared with other work, no GPU",
                       "3.11.7", "2.4.6", "numba 0.68.1, Warp 1.19.0 (CPU)"),
    "H100": Machine("NVIDIA H100 80GB HBM3 (driver 580.159.04), 16-core Intel Xeon host",
                    "3.12.3", "2.4.6", "numba 0.68.0, numba-cuda 0.30.4, Warp 1.19.0"),
    "H100, NumPy 2.5": Machine("NVIDIA H100 80GB HBM3 (driver 580.159.04), 16-core Intel Xeon host",
                               "3.12.3", "2.5.2", "numba 0.68.0, Warp 1.19.0"),
    "H200": Machine("NVIDIA H200 of the same pool (driver 580.159.04), 16-core Intel Xeon host",
                    "3.12.3", "2.4.6", "numba 0.68.0, numba-cuda 0.30.4, Warp 1.19.0"),
    "H200, NumPy 2.5": Machine("NVIDIA H200 of the same pool (driver 580.159.04), 16-core Intel Xeon host",
                               "3.12.3", "2.5.2", "numba 0.68.0, Warp 1.19.0"),
}


@dataclass(frozen=True)
class Source:
    machine: str
    commit: str  # the code measured, as the history page records it; else the commit that added the file
    command: str
    date: str = ""  # only for files that do not record their own (``machine.date``)


#: The file behind each table, named by hand. "Newest" cannot be read from the files alone: they
#: record the day of their run (``machine.date``, and not all of them) but not the commit, one day
#: holds several runs of a kind (before/after pairs, variants tried and reverted), and some files
#: are a baseline rather than the code that shipped. So each kind's newest file is chosen here,
#: with the commit of its code from the history page (or, where that names none, from
#: ``git log --diff-filter=A`` of the file). A new run of a kind replaces its line.
SOURCES = {
    # Packing at scale, H100
    "round_time_h100_issue20_step10c.json": Source(
        "H100", "53b8133", "python3 bench/round_time.py --mesh armadillo.obj --count 100000 "
        "--backends warp numba-cuda numba --versions now=. --repeats 3", "2026-11-25"),
    "round_time_h100_cube_issue20_step7.json": Source(
        "H100", "4ea141e", "python3 bench/round_time.py --mesh cube --count 100000 "
        "--backends warp numba-cuda numba --versions now=. --repeats 2", "2026-11-25"),
    # Issue 48's second step: bench/gpu_issue48_step2.sh MODE on one day, by the code of each file.
    **{name: Source("H100, NumPy 2.5", commit, f"bash bench/gpu_issue48_step2.sh {mode}", "2026-11-27")
       for name, commit, mode in [
           ("profile_kernels_h100_armadillo_issue48_step2.json", "3ffe337", "armadillo"),
           ("profile_kernels_h100host_numba_armadillo_issue48_step2.json", "3ffe337", "armadillo")]},
    # Issue 48's cooperative walks: bench/gpu_issue48_step4.sh MODE (step3.sh: moves only, the constants' run).
    **{name: Source("H100, NumPy 2.5", "5c7e1fc", f"bash bench/gpu_issue48_step4.sh {mode}", "2026-11-27")
       for name, mode in [("profile_kernels_h100_armadillo_issue48_step4.json", "lanes"),
                          ("profile_kernels_h100host_numba_armadillo_issue48_step4.json", "lanes"),
                          ("million_h100_armadillo_issue48_step4.json", "million")]},
    **{name: Source("H200, NumPy 2.5", "39d016d", f"bash bench/gpu_issue48_step4.sh {mode}", "2026-11-27")
       for name, mode in [("profile_kernels_h200_armadillo_issue48_step4.json", "lanes"),
                          ("profile_kernels_h200host_numba_armadillo_issue48_step4.json", "lanes"),
                          ("million_h200_armadillo_issue48_step4.json", "million")]},
    # Issue 48's sixth step (a move launch's chain): bench/gpu_issue48_step6.sh on one H100 lease, two runs:
    # af1a36d against bf23c2a (STEP=step6), then bf23c2a against c93efeb (STEP=step6b), then c93efeb alone.
    **{f"{case}_h100_issue48_step6_base.json": Source(
        "H100, NumPy 2.5", "af1a36d", "bash bench/gpu_issue48_step6.sh measure", "2026-11-27")
       for case in ("armadillo_100k", "armadillo_1m", "cube_1m")},
    **{name: Source("H100, NumPy 2.5", "bf23c2a", command, "2026-11-27") for name, command in [
        *[(f"{case}_h100_issue48_step6_now.json", "bash bench/gpu_issue48_step6.sh measure")
          for case in ("armadillo_100k", "armadillo_1m", "cube_1m")],
        *[(f"{case}_h100_issue48_step6b_base.json", "STEP=step6b bash bench/gpu_issue48_step6.sh measure")
          for case in ("armadillo_100k", "armadillo_1m", "cube_1m")],
        ("profile_kernels_h100_armadillo_issue48_step6.json", "bash bench/gpu_issue48_step6.sh profile")]},
    **{name: Source("H100, NumPy 2.5", "c93efeb", command, "2026-11-27") for name, command in [
        *[(f"{case}_issue48_step6b_now.json", "STEP=step6b bash bench/gpu_issue48_step6.sh measure")
          for case in ("armadillo_100k_h100", "armadillo_100k_h100host_numba", "armadillo_1m_h100", "cube_1m_h100",
                       "square_1m_h100")],
        *[(f"{case}_1m_h100host_numba_issue48_step6b_now.json", "STEP=step6b bash bench/gpu_issue48_step6.sh numba")
          for case in ("cube", "square")],
        ("armadillo_100k_h100_issue48_step6_repeats_now.json", "python3 bench/profile_kernels.py --backends warp "
         "--mesh armadillo.obj --count 100000 --repeats 7 --stages --no-profiled")]},
    # Then Warp's launches replayed and restarts floored (8a198b3) against c93efeb on two more leases: STEP=step6c
    # (measure, numba, and 7 runs of each), STEP=step6d (turns).
    **{name: Source("H100, NumPy 2.5", "c93efeb", command, "2026-11-27") for name, command in [
        *[(f"{case}_h100_issue48_step6c_base.json", "STEP=step6c bash bench/gpu_issue48_step6.sh measure")
          for case in ("armadillo_100k", "armadillo_1m", "cube_1m")],
        ("armadillo_100k_h100_issue48_step6c_repeats_base.json", "python3 bench/profile_kernels.py --backends warp "
         "--mesh armadillo.obj --count 100000 --repeats 7 --stages --no-profiled"),
        *[(f"armadillo_100k_h100_issue48_step6d_pass{k}_base.json", "STEP=step6d bash bench/gpu_issue48_step6.sh turns")
          for k in (1, 2)]]},
    **{name: Source("H100, NumPy 2.5", "8a198b3", command, "2026-11-27") for name, command in [
        *[(f"{case}_issue48_step6c_now.json", "STEP=step6c bash bench/gpu_issue48_step6.sh measure")
          for case in ("armadillo_100k_h100", "armadillo_100k_h100host_numba", "armadillo_1m_h100", "cube_1m_h100",
                       "square_1m_h100")],
        *[(f"{case}_1m_h100host_numba_issue48_step6c_now.json", "STEP=step6c bash bench/gpu_issue48_step6.sh numba")
          for case in ("cube", "square")],
        ("armadillo_100k_h100_issue48_step6c_repeats_now.json", "python3 bench/profile_kernels.py --backends warp "
         "--mesh armadillo.obj --count 100000 --repeats 7 --stages --no-profiled"),
        *[(name, "STEP=step6d bash bench/gpu_issue48_step6.sh turns") for name in (
            "armadillo_100k_h100_issue48_step6d_pass1_now.json", "armadillo_100k_h100_issue48_step6d_pass2_now.json",
            "armadillo_100k_h100host_numba_issue48_step6d_now.json",
            "armadillo_100k_h100_issue48_step6d_pass3_now.json")]]},
    # Issue 48's seventh step (a round's host work): bench/gpu_issue48_step7.sh on two H100 leases, this code
    # (1e767cb) against 9d800f2: measure on the first, STEP=step7b final on the second.
    **{name: Source("H100, NumPy 2.5", "9d800f2", command, "2026-11-27") for name, command in [
        *[(f"{case}_h100_issue48_step7_{kind}base.json", "bash bench/gpu_issue48_step7.sh measure")
          for case, kind in (("armadillo_100k", "pass1_"), ("armadillo_100k", "pass2_"), ("armadillo_1m", ""),
                             ("cube_1m", ""))],
        ("armadillo_100k_h100_issue48_step7b_base.json", "STEP=step7b bash bench/gpu_issue48_step7.sh final")]},
    **{name: Source("H100, NumPy 2.5", "1e767cb", command, "2026-11-27") for name, command in [
        *[(f"{case}_issue48_step7_{kind}now.json", "bash bench/gpu_issue48_step7.sh measure")
          for case, kind in (("armadillo_100k_h100", "pass1_"), ("armadillo_100k_h100", "pass2_"),
                             ("armadillo_100k_h100", "reach_"), ("armadillo_100k_h100host_numba", ""),
                             ("armadillo_1m_h100", ""), ("cube_1m_h100", ""), ("square_1m_h100", ""))],
        ("profile_kernels_h100_armadillo_issue48_step7.json", "bash bench/gpu_issue48_step7.sh measure"),
        *[(f"{case}_issue48_step7b_now.json", "STEP=step7b bash bench/gpu_issue48_step7.sh final")
          for case in ("armadillo_100k_h100", "armadillo_100k_h100host_numba", "armadillo_1m_h100", "cube_1m_h100",
                       "cube_1m_h100host_numba", "square_1m_h100", "square_1m_h100host_numba")]]},
    "armadillo_100k_h100_backends_issue48_step7c_now.json": Source(
        "H100", "1e767cb", "STEP=step7c bash bench/gpu_issue48_step7.sh cuda", "2026-11-27"),
    **{f"{case}_1m_h100_backends_issue48_step7c_now.json": Source(
        "H100", "6b13fee", "STEP=step7c bash bench/gpu_issue48_step7.sh cuda-million", "2026-11-27")
       for case in ("armadillo", "cube", "square")},
    "compile_options_h100_numba_cuda_issue48.json": Source(
        "H100", "e785e8a", "bash bench/gpu_issue48_step7.sh cuda-compile", "2026-11-27"),
    # Issue 48's eighth step (numba-cuda's cooperative walk): bench/gpu_issue48_step8.sh on one H100 lease, NumPy 2.4
    # carried, this code (640ce8f) against cf9e21a.
    "armadillo_100k_h100_numba_cuda_issue48_step8_base.json": Source(
        "H100", "cf9e21a", "bash bench/gpu_issue48_step8.sh cuda", "2026-11-27"),
    "cuda_compile_h100_issue48_step8_base.json": Source(
        "H100", "cf9e21a", "bash bench/gpu_issue48_step8.sh compile", "2026-11-27"),
    **{name: Source("H100", "640ce8f", f"bash bench/gpu_issue48_step8.sh {mode}", "2026-11-27") for name, mode in [
        ("armadillo_100k_h100_numba_cuda_issue48_step8_now.json", "cuda"),
        ("armadillo_100k_h100_backends_issue48_step8_now.json", "cuda"),
        ("cuda_compile_h100_issue48_step8_now.json", "compile"),
        *[(f"{case}_1m_h100_backends_issue48_step8_now.json", "million") for case in ("armadillo", "cube", "square")],
        ("armadillo_100k_h100_backends_issue48_step8b_now.json", "backends")]},
    # The review mend (a7d7ae2: one node-visit text, the smallest element through the float minimum) against 22ea1af,
    # on another lease: its own first run, then base and now in turn twice (the second pass's files).
    "armadillo_100k_h100_numba_cuda_issue48_step8c_now.json": Source(
        "H100", "a7d7ae2", "python3 bench/profile_kernels.py --stages --no-profiled --backends numba-cuda --mesh "
        "armadillo.obj --count 100000 --repeats 3", "2026-11-27"),
    **{f"armadillo_100k_h100_numba_cuda_issue48_step8c_turn_{version}.json": Source(
        "H100", commit, "source bench/gpu_header.sh; for v in base now base now; do kernels $v "
        "armadillo_100k_h100_numba_cuda_issue48_step8c_turn --backends numba-cuda --mesh armadillo.obj --count 100000 "
        "--repeats 3; done", "2026-11-27") for version, commit in (("base", "22ea1af"), ("now", "a7d7ae2"))},
    "cuda_compile_2core_issue48_step8.json": Source(
        "2 cores", "640ce8f", "python bench/cuda_compile.py --shape mesh --grid 6 --count 40 --ptxas "
        "/usr/local/cuda-13.0/bin/ptxas --out bench/results/cuda_compile_2core_issue48_step8.json"),
    # Issue 48's ninth step (numba-cuda's compile): bench/gpu_issue48_step9.sh, NumPy 2.4 carried, against 213591c.
    **{f"cuda_compile_h100_issue48_step9_{version}.json": Source(
        "H100", commit, "bash bench/gpu_issue48_step9.sh compile", "2026-11-27")
       for version, commit in (("base", "213591c"), ("now", "0b2cd93"))},
    **{f"armadillo_100k_h200_numba_cuda_issue48_step9_turn{turn}_{version}.json": Source(
        "H200", commit, "bash bench/gpu_issue48_step9.sh cuda", "2026-11-27")
       for turn in (1, 2) for version, commit in (("base", "213591c"), ("now", "0b2cd93"))},
    "armadillo_100k_h200_backends_issue48_step9_now.json": Source(
        "H200", "0b2cd93", "bash bench/gpu_issue48_step9.sh cuda", "2026-11-27"),
    **{f"fresh_machine_h100_issue48_step9b_{version}.json": Source(
        "H100", commit, "STEP=step9b bash bench/gpu_issue48_step9.sh fresh", "2026-11-27")
       for version, commit in (("base", "213591c"), ("now", "367b374"))},
    **{f"armadillo_100k_h100_numba_cuda_issue48_step9b_turn1_{version}.json": Source(
        "H100", commit, "STEP=step9b bash bench/gpu_issue48_step9.sh cuda (its first turn)", "2026-11-27")
       for version, commit in (("base", "213591c"), ("now", "367b374"))},
    **{f"fresh_machine_2core_issue48_step9_{version}.json": Source(
        "2 cores", commit, f"python bench/fresh_machine.py --mesh armadillo.obj --backends numba --out "
        f"bench/results/fresh_machine_2core_issue48_step9_{version}.json", "2026-11-27")
       for version, commit in (("base", "213591c"), ("now", "367b374"))},
    "armadillo_100k_h100_backends_issue48_step9c_now.json": Source(
        "H100", "367b374", "STEP=step9c bash bench/gpu_issue48_step9.sh backends", "2026-11-27"),
    **{f"armadillo_100k_h100_numba_cuda_issue48_step9c_turn{turn}_{version}.json": Source(
        "H100", commit, "source bench/gpu_header.sh; issue48_inputs; for turn in 1 2; do for v in base now; do "
        "kernels $v armadillo_100k_h100_numba_cuda_issue48_step9c_turn$turn --backends numba-cuda --mesh "
        "/tmp/armadillo.obj --count 100000 --repeats 3; done; done", "2026-11-27")
       for turn in (1, 2) for version, commit in (("base", "213591c"), ("now", "367b374"))},
    **{f"fresh_machine_h100_issue48_step9d_{version}.json": Source(
        "H100", commit, "STEP=step9d bash bench/gpu_issue48_step9.sh warp", "2026-11-27")
       for version, commit in (("base", "1b1777e"), ("now", "ba917bf"))},
    **{f"armadillo_100k_h100_warp_issue48_step9d_turn{turn}_{version}.json": Source(
        "H100", commit, "STEP=step9d bash bench/gpu_issue48_step9.sh warp", "2026-11-27")
       for turn in (1, 2) for version, commit in (("base", "1b1777e"), ("now", "ba917bf"))},
    # Issue 48's tenth step (the kernels written once): bench/gpu_issue48_step10.sh on H100s, NumPy 2.4 carried,
    # against 96d6760; the turns with the final code (0273d65), the fresh machine with it less its index changes (the
    # guard as a flag, the box read once), which came after on the same day.
    **{f"armadillo_100k_h100_{backend}_issue48_step10c_turn{turn}_{version}.json": Source(
        "H100", commit, "STEP=step10c bash bench/gpu_issue48_step10.sh turns", "2026-11-28")
       for version, commit in (("base", "96d6760"), ("now", "0273d65")) for backend in ("warp", "numba_cuda")
       for turn in (1, 2)},
    "armadillo_100k_h100_backends_issue48_step10c_now.json": Source(
        "H100", "0273d65", "STEP=step10c bash bench/gpu_issue48_step10.sh turns", "2026-11-28"),
    **{f"fresh_machine_h100_issue48_step10_{version}.json": Source(
        "H100", commit, "bash bench/gpu_issue48_step10.sh fresh", "2026-11-28")
       for version, commit in (("base", "96d6760"), ("now", "0273d65 less its index changes"))},
    # Issue 48's eleventh step: bench/gpu_issue48_step11.sh on H100s, NumPy 2.4 carried; the base 64cf4e0; the Warp
    # level-3 tier kept aside at 1fbb251 (not on main).
    **{name: Source("H100", "64cf4e0", f"bash bench/gpu_issue48_step11.sh {mode}", "2026-11-28") for name, mode in (
        ("where_h100_warp_issue48_step11.json", "where"), ("where_h100_numba_cuda_issue48_step11.json", "where"),
        ("armadillo_100k_h100_backends_issue48_step11_where.json", "where"),
        ("compile_options_h100_issue48_step11.json", "levels"),
        *[(f"armadillo_100k_h100_numba_cuda_deallocs{count}_issue48_step11_turn{turn}_now.json", "deallocs")
          for count in (10, 1000000) for turn in (1, 2)],
        *[(f"armadillo_100k_h100_numba_cuda_issue48_step11_turn{turn}_base.json", "flush") for turn in (1, 2)])},
    **{name: Source("H100", "a89e925", "bash bench/gpu_issue48_step11.sh flush", "2026-11-28") for name in (
        "armadillo_100k_h100_numba_cuda_issue48_step11_turn1_now.json",
        "armadillo_100k_h100_numba_cuda_issue48_step11_turn2_now.json",
        "armadillo_100k_h100_backends_issue48_step11_flush.json")},
    **{name: Source("H100", "1fbb251", "git checkout 1fbb251 && bash bench/gpu_issue48_step11.sh tiers; ... turns "
                    "(on main: bash bench/gpu_issue48_step11.sh level-turns)", "2026-11-28")
       for name in ("compile_tiers_h100_issue48_step11.json",
                    *[f"armadillo_100k_h100_warp_issue48_step11tiers_turn{turn}_{version}.json"
                      for turn in (1, 2) for version in ("base", "now")])},
    **{f"{case}_1m_h100_backends_issue48_step11_now.json": Source(
        "H100", "a89e925", "bash bench/gpu_issue48_step11.sh million", "2026-11-28")
       for case in ("armadillo", "cube", "square")},
    # Issue 48's twelfth step (compile helpers): bench/gpu_issue48_step12.sh on one H100 lease, NumPy 2.4 carried,
    # against 4d9dd08 in turns.
    **{f"fresh_machine_h100_issue48_step12_turn{turn}_{version}.json": Source(
        "H100", commit, "bash bench/gpu_issue48_step12.sh fresh", "2026-11-28")
       for turn in (1, 2) for version, commit in (("base", "4d9dd08"), ("now", "19d892d less its mesh notice"))},
    **{name: Source("H100", "19d892d less its mesh notice", "bash bench/gpu_issue48_step12.sh check", "2026-11-28")
       for name in ("armadillo_100k_h100_backends_issue48_step12_now.json",)},
    **{f"fresh_machine_h100_issue48_step12b_turn{turn}_{version}.json": Source(
        "H100", commit, "STEP=step12b bash bench/gpu_issue48_step12.sh fresh", "2026-11-28")
       for turn in (1, 2) for version, commit in (("base", "4d9dd08"), ("now", "5dba687"))},
    **{f"hard_h100_{backend}_issue48_step12_turn{turn}.json": Source(
        "H100", "7e5176d (kept aside, not on main)", "git checkout 7e5176d && bash bench/gpu_issue48_step12.sh hard",
        "2026-11-28") for backend in ("warp", "numba_cuda") for turn in (1, 2)},
    # Issue 48's thirteenth step (the final check's distances while the device moves): bench/gpu_issue48_step13.sh on
    # one H200 lease, NumPy 2.4 carried, against d9806d9 in turns.
    **{f"{case}_issue48_step13c_turn{turn}_{version}.json": Source(
        "H200", commit, f"STEP=step13c bash bench/gpu_issue48_step13.sh {mode}", "2026-11-28")
       for case, mode in (("armadillo_100k_h200", "check"), ("armadillo_1m_h200_warp", "million"),
                          ("cube_1m_h200_warp", "million"))
       for turn in (1, 2) for version, commit in (("base", "d9806d9"), ("now", "9ec2ef8"))},
    **{f"timeline_h100_{backend}_issue48_step13.json": Source(
        "H100", "651ae88", "bash bench/gpu_issue48_step13.sh timeline", "2026-11-28")
       for backend in ("warp", "numba-cuda")},
    "armadillo_100k_h200_backends_issue48_step13c_now.json": Source(
        "H200", "9ec2ef8", "STEP=step13c bash bench/gpu_issue48_step13.sh check", "2026-11-28"),
    # Issue 48's fourteenth step (host work off the GPU's path): bench/gpu_issue48_step15.sh on H200 leases, NumPy
    # 2.4 carried: move block sizes and where the device waits (2c5acdd), the set-up's step in against 2c5acdd and
    # numba-cuda's copies against 2ee5c62 in turns, then the final code beside numba (cf4f8d3).
    **{f"{kind}_h200_{backend}_issue48_step15.json": Source(
        "H200", "2c5acdd", "bash bench/gpu_issue48_step15.sh blocks", "2026-11-28")
       for kind in ("blocks", "timeline") for backend in ("warp", "numba-cuda")},
    **{f"stack_h200_warp_{version}_issue48_step15.json": Source(
        "H200", "2aa7e1f", "bash bench/gpu_issue48_step15.sh stack", "2026-11-28")
       for version in ("installed", "noinit")},
    **{f"armadillo_100k_h200_issue48_step15_turn{turn}_{version}.json": Source(
        "H200", commit, "bash bench/gpu_issue48_step15.sh turns", "2026-11-28")
       for turn in (1, 2) for version, commit in (("base", "2c5acdd"), ("now", "f47f805"))},
    **{f"armadillo_100k_h200_issue48_step15b_turn{turn}_{version}.json": Source(
        "H200", commit, "STEP=step15b bash bench/gpu_issue48_step15.sh copies", "2026-11-28")
       for turn in (1, 2) for version, commit in (("base", "2ee5c62"), ("now", "cf4f8d3"))},
    **{name: Source("H200", "cf4f8d3", "STEP=step15b bash bench/gpu_issue48_step15.sh scale", "2026-11-28")
       for name in ("armadillo_100k_h200_backends_issue48_step15b_now.json",
                    "armadillo_1m_h200_gpus_issue48_step15b_now.json",
                    "armadillo_1m_h200_numba_issue48_step15b_now.json", "timeline_h200_warp_issue48_step15b_scale.json",
                    "verify_speed_h200_armadillo_100k_issue48_step15b.json")},
    **{name: Source("H200", "9c75fa8", f"bash bench/gpu_issue48_step16.sh {mode}", "2026-11-28")
       for name, mode in (("cube_1m_h200_backends_issue48_step16_base.json", "inline"),
                          ("square_1m_h200_backends_issue48_step16_base.json", "inline"),
                          ("cube_1m_h200_numba_issue48_step16_now.json", "million"),
                          ("square_1m_h200_numba_issue48_step16_now.json", "million"),
                          ("fresh_machine_h200_issue48_step16.json", "million"))},
    **{name: Source("H200", commit, "STEP=step16b bash bench/gpu_issue48_step16.sh inline", "2026-11-28")
       for version, commit in (("base", "9c75fa8"), ("now", "cc22473"))
       for name in (f"armadillo_100k_h200_warp_issue48_step16b_turn1_{version}.json",
                    f"armadillo_100k_h200_warp_issue48_step16b_turn2_{version}.json",
                    f"cube_1m_h200_backends_issue48_step16b_{version}.json",
                    f"square_1m_h200_backends_issue48_step16b_{version}.json")},
    **{f"fresh_machine_2core_issue48_step12_{version}.json": Source(
        "2 cores", commit, f"{'PYTHONPATH=<4d9dd08' + chr(39) + 's ndpack> ' if version == 'base' else ''}python "
        f"bench/fresh_machine.py --mesh armadillo.obj --backends numba --out "
        f"bench/results/fresh_machine_2core_issue48_step12_{version}.json", "2026-11-28")
       for version, commit in (("base", "4d9dd08"), ("now", "c9b18cc"))},
    "dense_beds_2core_issue49.json": Source(
        "2 cores", "dac52f0", "python bench/dense_beds.py --out bench/results/dense_beds_2core_issue49.json",
        "2026-11-28"),
    "work_model_2core_armadillo_100k_issue48_step11_walks.json": Source(
        "2 cores", "ebce931", "python bench/work_model.py --mesh armadillo.obj --count 100000 --parts walks"),
    "ahead_fraction_2core.json": Source(
        "2 cores", "1e767cb", "python bench/ahead_tail.py --starts 3e-4 --fractions 0.64 0.512 0.4 --large-seeds 3"),
    "work_model_2core_armadillo_100k_issue48_step14.json": Source(
        "2 cores", "d75f664", "python bench/work_model.py --mesh armadillo.obj --count 100000 --against "
        "bench/results/stack_h200_warp_installed_issue48_step15.json --constants "
        "bench/results/work_model_2core_armadillo_100k_issue48_step7.json"),
    "work_model_2core_armadillo_100k_issue48_step7.json": Source(
        "2 cores", "1e767cb", "python bench/work_model.py --mesh armadillo.obj --count 100000 --against "
        "bench/results/profile_kernels_h100_armadillo_issue48_step7.json --constants "
        "bench/results/work_model_2core_armadillo_100k_issue48_step5.json"),
    "ahead_tail_2core.json": Source("2 cores", "8a198b3", "python bench/ahead_tail.py"),
    "launch_cost_2core.json": Source("2 cores", "8a198b3", "python bench/launch_cost.py"),
    "work_model_2core_armadillo_100k_issue48_step6.json": Source(
        "2 cores", "8a198b3", "python bench/work_model.py --mesh armadillo.obj --count 100000 --against "
        "bench/results/profile_kernels_h100_armadillo_issue48_step6.json --constants "
        "bench/results/work_model_2core_armadillo_100k_issue48_step5.json"),
    # Issue 48's fifth step (the host's part of a round): bench/gpu_issue48_step5.sh final on an H100, and
    # measure on an H200 (this code against main before, 49cef62, in one run).
    **{name: Source("H100, NumPy 2.5", "d7c0654", "bash bench/gpu_issue48_step5.sh final", "2026-11-27")
       for name in ["armadillo_100k_h100_issue48_step5_now.json",
                    "armadillo_100k_h100host_numba_issue48_step5_now.json", "armadillo_1m_h100_issue48_step5_now.json",
                    "cube_1m_h100_issue48_step5_now.json", "cube_1m_h100host_numba_issue48_step5_now.json",
                    "square_1m_h100_issue48_step5_now.json", "square_1m_h100host_numba_issue48_step5_now.json"]},
    **{name: Source("H200, NumPy 2.5", commit, "bash bench/gpu_issue48_step5.sh measure", "2026-11-27")
       for name, commit in [("armadillo_100k_h200_issue48_step5_base.json", "49cef62"),
                            ("armadillo_1m_h200_issue48_step5_base.json", "49cef62"),
                            ("cube_1m_h200_issue48_step5_base.json", "49cef62"),
                            ("armadillo_100k_h200_issue48_step5_now.json", "d7c0654"),
                            ("armadillo_1m_h200_issue48_step5_now.json", "d7c0654"),
                            ("cube_1m_h200_issue48_step5_now.json", "d7c0654")]},
    "profile_kernels_h200_armadillo_issue48_step5.json": Source(
        "H200, NumPy 2.5", "d7c0654", "bash bench/gpu_issue48_step5.sh profile", "2026-11-27"),
    "work_model_2core_armadillo_100k_issue48_step5.json": Source(
        "2 cores", "d7c0654", "python bench/work_model.py --mesh armadillo.obj --count 100000 --against "
        "bench/results/profile_kernels_h200_armadillo_issue48_step5.json --constants "
        "bench/results/work_model_2core_armadillo_100k_issue48_step4.json"),
    "profile_kernels_h200_armadillo_issue48_step3.json": Source(
        "H200, NumPy 2.5", "5d70ad2", "bash bench/gpu_issue48_step3.sh lanes", "2026-11-27"),
    "cooperative_walk_2core_armadillo.json": Source("2 cores", "5d70ad2", "python bench/cooperative_walk.py"),
    **{f"work_model_2core_armadillo_100k_issue48_{step}.json": Source(
        "2 cores", "39d016d", "python bench/work_model.py --mesh armadillo.obj --count 100000 "
        f"--against bench/results/profile_kernels_h200_armadillo_issue48_{step}.json" + constants)
       for step, constants in [("step3", ""), ("step4", " --constants bench/results/"
                                               "work_model_2core_armadillo_100k_issue48_step3.json")]},
    "profile_kernels_h100_armadillo_issue48_before.json": Source(
        "H100, NumPy 2.5", "e08d8b4", "python3 bench/profile_kernels.py --backends warp numba --mesh armadillo.obj "
        "--count 100000 --repeats 3 --stages --host-profile", "2026-11-27"),
    "work_model_2core_armadillo_100k_issue48_before.json": Source(
        "2 cores", "e08d8b4", "python bench/work_model.py --mesh armadillo.obj --count 100000 "
        "--against bench/results/profile_kernels_h100_armadillo_issue48_before.json"),
    "work_model_2core_armadillo_100k_issue48_step2.json": Source(
        "2 cores", "3ffe337", "python bench/work_model.py --mesh armadillo.obj --count 100000 "
        "--against bench/results/profile_kernels_h100_armadillo_issue48_step2.json "
        "--constants bench/results/work_model_2core_armadillo_100k_issue48_before.json"),
    "policy_fill_2core_10k.json": Source("2 cores", "1e767cb", "python bench/policy_fill.py --count 10000 --seeds 3"),
    "compile_options_h100_issue48.json": Source(
        "H100, NumPy 2.5", "3ffe337", "python3 bench/compile_options.py --mesh armadillo.obj --variants O2 default "
        "--count 100000 --repeats 3"),
    "scale_million_h100_warp_issue46.json": Source(
        "H100, NumPy 2.5", "4210e2b", "bash bench/gpu_issue46.sh warp", "2026-11-27"),
    "scale_million_h100_numba_issue46.json": Source(
        "H100, NumPy 2.5", "4210e2b", "bash bench/gpu_issue46.sh numba", "2026-11-27"),
    "profile_kernels_h100_armadillo_issue48.json": Source("H100, NumPy 2.5", "95b5a5f", "bash bench/gpu_issue48.sh"),
    "work_model_2core_armadillo_100k.json": Source(
        "2 cores", "95b5a5f", "python bench/work_model.py --mesh armadillo.obj --count 100000 "
        "--against bench/results/profile_kernels_h100_armadillo_issue48.json"),
    "profile_kernels_h200_armadillo_issue48.json": Source("H200, NumPy 2.5", "993d9c9", "bash bench/gpu_issue48.sh"),
    "profile_kernels_h200_armadillo20k_issue48.json": Source(
        "H200, NumPy 2.5", "993d9c9", "bash bench/gpu_issue48.sh small"),
    "work_model_2core_armadillo_100k_h200.json": Source(
        "2 cores", "993d9c9", "python bench/work_model.py --mesh armadillo.obj --count 100000 "
        "--against bench/results/profile_kernels_h200_armadillo_issue48.json"),
    "work_model_2core_armadillo20k_100k_h200.json": Source(
        "2 cores", "993d9c9", "python bench/work_model.py --mesh tests/data/meshes/armadillo-20k.ply --count 100000 "
        "--constants bench/results/work_model_2core_armadillo_100k_h200.json "
        "--against bench/results/profile_kernels_h200_armadillo20k_issue48.json"),
    "tiled_1M_h100_warp.json": Source("H100", "e7f6fee", "bash bench/gpu_issue25.sh gpu"),
    "tiled_1M_h100_numba.json": Source("H100", "e7f6fee", "bash bench/gpu_issue25.sh cpu"),
    "tiled_10M_h100_warp_alone.json": Source(
        "H100", "e7f6fee", "python3 bench/tiled.py --count 10000000 --workers 8 --backend warp --device cuda:0"),
    "tiled_10M_h100_warp_8.json": Source(
        "H100", "e7f6fee", "python3 bench/tiled.py --count 10000000 --workers 8 --backend warp --device cuda:0 "
        "--no-alone"),
    "tiled_10M_h100_warp_16.json": Source(
        "H100", "e7f6fee", "python3 bench/tiled.py --count 10000000 --workers 16 --backend warp --device cuda:0 "
        "--no-alone"),
    "profile_kernels_h100_issue20_step10.json": Source(
        "H100", "53b8133", "python3 bench/profile_kernels.py --backends warp numba-cuda --mesh armadillo.obj "
        "--count 100000", "2026-11-25"),
    # Packing at scale, 2 cores
    "round_time_2core_issue20_step10.json": Source(
        "2 cores", "53b8133", "python bench/round_time.py --mesh armadillo.obj --count 100000 --backends numba "
        "--versions now=. --repeats 3", "2026-11-25"),
    "fast_tuning_2core_cube.json": Source(
        "2 cores", "d3149d8", "python bench/fast_tuning.py --count 100000 --seeds 0 1 "
        "--variants now:2e-5/1e-4/1024/0.0625"),
    "tiled_2core.json": Source("2 cores", "355174e", "python bench/tiled.py --count 200000 --workers 1 2"),
    "scale_million_2core.json": Source(
        "2 cores", "5115451", "python bench/scale.py --cases cube --backends numba --box-count 1000000"),
    "scale_nd_subdivided_2core.json": Source(
        "2 cores", "76374f5", "python bench/scale.py --cases nd armadillo-subdivided --backends numba "
        "--nd-count 100000 --faithful-count 0 --time-budget 500"),
    # Other shapes and dimensions, H100 (the fifth measurement of issue 5)
    **{f"scale_{kind}_h100_{backend}.json": Source(
        "H100", "9aafdd1", "bash bench/gpu_extra.sh {boxes,subdivided,nd} {warp,numba-cuda}")
       for kind in ("boxes", "subdivided", "nd") for backend in ("warp", "numba-cuda")},
    # Modes, start-up, kernels
    "auto_mode_2core.json": Source(
        "2 cores", "d8f890e", "python bench/auto_mode.py --mesh ../shared/data/meshes/cow.obj --repeats 3"),
    "fast_fill_2core_issue47.json": Source(
        "2 cores", "07a53d4", "python bench/fast_fill.py --counts 100 1000 --seeds 3 (and --counts 10000 --seeds 1 "
        "--dims 4 5; --dims 3 4 for the periodic box)"),
    "index_speed_2core_issue47.json": Source(
        "2 cores", "e557e8c", "python bench/index_speed.py --before e557e8c~1 --repeats 3"),
    **{f"index_queries_{d}d_2core_issue47.json": Source(
        "2 cores", "e557e8c", "python bench/index_speed.py --queries {3,4,5} --at 60000 --before e557e8c~1")
       for d in (3, 4, 5)},
    "index_speed_h100_warp_versions_issue47.json": Source(
        "H100, NumPy 2.5", "e557e8c", "bash bench/gpu_issue47.sh window"),
    "index_speed_h100host_numba_issue47.json": Source(
        "H100, NumPy 2.5", "e557e8c", "bash bench/gpu_issue47.sh host"),
    "threads_2core_quiet.json": Source("2 cores", "efd1d94", "python bench/threads.py --repeats 3"),
    "threads_2core_load2.json": Source("2 cores", "efd1d94", "python bench/threads.py --repeats 3 --load 2"),
    "threads_2core_load4.json": Source("2 cores", "efd1d94", "python bench/threads.py --repeats 3 --load 4"),
    "threads_h100host_issue47.json": Source("H100, NumPy 2.5", "e557e8c", "bash bench/gpu_issue47.sh host"),
    "auto_mode_threads_quiet_2core_issue47.json": Source(
        "2 cores", "e557e8c", "python bench/auto_mode.py --modes auto --one-thread --repeats 3"),
    "auto_mode_threads_load2_2core_issue47.json": Source(
        "2 cores", "e557e8c", "python bench/auto_mode.py --modes auto --one-thread --repeats 3 --load 2"),
    "voxel_speed_2core_issue47.json": Source("2 cores", "e557e8c", "python bench/voxel_speed.py"),
    "conflicts_2core_issue47.json": Source("2 cores", "8d1c427", "python bench/conflicts.py"),
    "fast_fill_2core_issue47_10k.json": Source(
        "2 cores", "e557e8c", "python bench/fast_fill.py --counts 10000 --seeds 1 --dims 6 --shapes 'ball with a hole' "
        "simplex 'csg part' --out FILE, then --dims 3 4 --shapes 'periodic box, radii 0.03-0.2' --out FILE --append"),
    "compile_cache_2core_issue19.json": Source(
        "2 cores", "e172723", "python bench/compile_cache.py", "2026-11-24"),
    **{f"compile_cache_2core_issue48_step12{suffix}.json": Source(
        "2 cores", commit, f"{prefix}python bench/compile_cache.py --out "
        f"bench/results/compile_cache_2core_issue48_step12{suffix}.json", "2026-11-28") for suffix, commit, prefix in (
            ("", "c9b18cc", ""), ("_base", "4d9dd08", "PYTHONPATH=<4d9dd08's ndpack> "))},
    "compile_cache_h100_issue19.json": Source("H100", "e172723", "bash bench/gpu_issue19.sh start", "2026-11-24"),
    "tape_speed_2core_issue19.json": Source(
        "2 cores", "e172723", "python bench/tape_speed.py --backends numba warp:cpu --points 400000 "
        "--spheres 2000 --repeats 3 --shapes demo deep mesh"),
    "tape_speed_h100_issue19.json": Source("H100", "e172723", "bash bench/gpu_issue19.sh speed"),
    "mesh_queries_h200.json": Source("H200", "a2d71aa", "bash bench/gpu_meshes.sh"),
    "mesh_queries_2core.json": Source(
        "2 cores", "39ddced", "python bench/mesh_queries.py --points 100000 --repeats 3"),
    # Faithful mode, fill against count
    "fill_vs_count.json": Source(
        "2 cores", "3e6a8fd", "python bench/fill_vs_count.py --n2 5000 --n3 3000 --seed 0 --out bench/results"),
    # Pictures, beds, coverings, many parts, tiles
    "render_speed_2core.json": Source("2 cores", "5cbe0ef", "python bench/render_speed.py --repeats 5"),
    "render_speed_h100host.json": Source("H100", "573a004", "bash bench/gpu_issue6.sh render"),
    "dem_fill_2core_issue22b.json": Source(
        "2 cores", "5d15942", "python bench/dem_fill.py --backends numba --fractions 0.5 0.6", "2026-11-25"),
    "dem_fill_h100_issue22.json": Source(
        "H100", "5d15942", "python bench/dem_fill.py --backends numba warp numba-cuda --device cuda:0 "
        "--fractions 0.5 0.6", "2026-11-25"),
    "cover_2core.json": Source("2 cores", "1d79145", "python bench/cover.py"),
    "cover_2core_times.json": Source(
        "2 cores", "a66c546", "python bench/cover.py --tolerances 0.01 0.005 --counts --no-baseline --repeats 5"),
    "many_parts_2core.json": Source("2 cores", "a5b9b48", "python bench/many_parts.py --workers 1 2 --count 2000"),
    "many_parts_h100.json": Source(
        "H100", "e7f6fee", "NDPACK_BACKEND=numba python3 bench/many_parts.py --workers 1 2 4 8 16 --count 2000 "
        "--no-meshes"),
    "tiled_mesh_2core.json": Source(
        "2 cores", "688b04b", "python bench/tiled_mesh.py --mesh cow.obj --count 20000 --workers 1 2"),
}


def load(name: str) -> dict:
    if name not in SOURCES:
        raise KeyError(f"{name} is not in SOURCES: name its machine, commit and command there first")
    return json.loads((RESULTS / name).read_text())


def versions(name: str) -> str:
    """Python and NumPy as the file records them (else the machine's), then the libraries."""
    data, machine = load(name), MACHINES[SOURCES[name].machine]
    recorded = data.get("machine") if isinstance(data.get("machine"), dict) else data.get("versions") or {}
    return (f"Python {recorded.get('python', machine.python)}, NumPy {recorded.get('numpy', machine.numpy)}, "
            f"{machine.libraries}")


def date(name: str) -> str:
    data = load(name)
    recorded = data.get("machine", {}).get("date") if isinstance(data.get("machine"), dict) else None
    return recorded or SOURCES[name].date or "not recorded"


def _run(name: str) -> tuple:
    return SOURCES[name].machine, SOURCES[name].commit, date(name), versions(name)


_cited: set[str] = set()  # the files whose sources the page lists so far


def sources(*names: str) -> list[str]:
    """A line per run: its results files, machine and versions, the commit measured, the commands.

    Neighbouring files of one machine, commit and day share a line."""
    _cited.update(names)
    groups: list[list[str]] = []
    for name in names:
        if groups and _run(groups[-1][0]) == _run(name):
            groups[-1].append(name)
        else:
            groups.append([name])
    lines = []
    for group in groups:
        what = SOURCES[group[0]]
        files = ", ".join(f"[`{name}`](../bench/results/{name})" for name in group)
        commands = "; ".join(f"`{command}`" for command in dict.fromkeys(SOURCES[name].command for name in group))
        lines.append(f"- {files}: {what.machine}, {versions(group[0])}; code `{what.commit}`, run {date(group[0])}; "
                     f"{commands}")
    return lines + [""]


def table(head: list[str], rows: list[list[str]]) -> list[str]:
    """A Markdown table; a column whose cells all start with a number (or are empty) aligns right."""
    def numeric(column):
        cells = [row[column] for row in rows if row[column]]
        return bool(cells) and all(NUMBER.match(cell) for cell in cells)
    rule = ["---:" if numeric(i) else "---" for i in range(len(head))]
    return ["| " + " | ".join(cells) + " |" for cells in (head, rule, *rows)] + [""]


def seconds(value: float | None) -> str:
    if value is None:
        return ""
    if value < 10:
        return f"{value:.2f} s"
    return f"{value:.1f} s" if value < 100 else f"{value:,.0f} s"


def count(value: int) -> str:
    return f"{value:,}"


def median_of(rows: list[dict], key: str = "seconds", **where) -> float | None:
    values = [row[key] for row in rows if all(row.get(k) == v for k, v in where.items())]
    return statistics.median(values) if values else None


def first(rows: list[dict], **where) -> dict:
    return next(row for row in rows if all(row.get(k) == v for k, v in where.items()))


# ----------------------------------------------------------------------------------------------
# Sections


def intro() -> list[str]:
    lines = [
        "# Benchmarks",
        "",
        "<!-- Written by bench/make_benchmarks.py from bench/results; edit the script, not this page. -->",
        "",
        "Today's figures: for each kind of measurement, the newest results file in `bench/results`. Under",
        "each table are its files, with the machine and versions, the commit whose code was measured and the",
        "command that reproduces them; where that commit is old, later code was not measured that way. The",
        "steps that led here, with the figures of older code, are in [benchmarks-history.md](benchmarks-history.md).",
        "Every packing passed the final float64 check. One code's times moved between leases of one machine",
        "kind (the history has examples), so compare within a table. Regenerate: `python bench/make_benchmarks.py`.",
        "",
        "## Machines",
        "",
    ]
    # The machines of the page's files (the other sections are written first: page()).
    rows = [[name, m.hardware, f"Python {m.python}, NumPy {m.numpy}, {m.libraries}"] for name, m in MACHINES.items()
            if name in {SOURCES[file].machine for file in _cited}]
    return lines + table(["machine", "hardware", "software"], rows)


def scale_h100() -> list[str]:
    cube = load("round_time_h100_cube_issue20_step7.json")["results"]
    # Issue 48's eleventh step, one H100 lease with NumPy 2.4 carried: the three backends in one process at
    # 100,000; Warp and numba-cuda at a million on the next lease.
    # Issue 48's fourteenth step: the armadillo's rows, the three backends on one H200 lease (cf4f8d3).
    backends15 = load("armadillo_100k_h200_backends_issue48_step15b_now.json")
    arm5, arm5_cuda, arm5_cpu = backends15["warp"], backends15["numba-cuda"], backends15["numba"]
    gpus_1m = load("armadillo_1m_h200_gpus_issue48_step15b_now.json")
    arm_1m, arm_1m_cuda = gpus_1m["warp"], gpus_1m["numba-cuda"]
    arm_1m_cpu = load("armadillo_1m_h200_numba_issue48_step15b_now.json")["numba"]
    # Issue 48's sixteenth step, one H200 lease: the cube and the square at a million, the GPUs in one process
    # (the first turn of `inline`, main's code), numba in the next (`million`), and the peak memory.
    million16 = {case: load(f"{case}_1m_h200_backends_issue48_step16_base.json") for case in ("cube", "square")}
    million16_cpu = {case: load(f"{case}_1m_h200_numba_issue48_step16_now.json")["numba"]
                     for case in ("cube", "square")}
    peak16 = dict(re.findall(r"(\w+) at 1,000,000: peak GPU memory used \(MiB, whole device\): (\d+)",
                             (RESULTS / "memory_h200_issue48_step16.txt").read_text()))
    # The sixteenth step's experiment: Warp's functions inlined, in turns with main (two turns at 100,000).
    inline = {(turn, version): load(f"armadillo_100k_h200_warp_issue48_step16b_turn{turn}_{version}.json")
              for turn in (1, 2) for version in ("base", "now")}
    inline_1m = {(case, version): load(f"{case}_1m_h200_backends_issue48_step16b_{version}.json")["warp"]
                 for case in ("cube", "square") for version in ("base", "now")}
    fresh16 = {row["backend"]: row for row in load("fresh_machine_h200_issue48_step16.json")["rows"]}
    # Issue 48's fourteenth step: host work off the GPU's path (the set-up's step in, numba-cuda's copies), in turns.
    step_in = {(turn, version): load(f"armadillo_100k_h200_issue48_step15_turn{turn}_{version}.json")
               for turn in (1, 2) for version in ("base", "now")}
    copies = {(turn, version): load(f"armadillo_100k_h200_issue48_step15b_turn{turn}_{version}.json")
              for turn in (1, 2) for version in ("base", "now")}
    blocks = {backend: load(f"blocks_h200_{backend}_issue48_step15.json")[f"{backend} now"]["kernels"]
              for backend in ("warp", "numba-cuda")}
    waits15 = load("timeline_h200_warp_issue48_step15b_scale.json")
    pairs15 = load("verify_speed_h200_armadillo_100k_issue48_step15b.json")["rows"][0]

    def in_turns(runs, backend, stage=None):
        def one(version):
            return ", ".join(seconds(runs[(turn, version)][backend]["median"] if stage is None
                                     else runs[(turn, version)][backend]["stages"][stage]) for turn in (1, 2))
        return f"{one('now')} against {one('base')}"

    stack = {version: load(f"stack_h200_warp_{version}_issue48_step15.json")["warp"]["kernels"]
             for version in ("installed", "noinit")}

    def per_launch(kernels, kind):
        """A profiled run's mean device time a launch of ``kind``."""
        calls, total = kernels[kind][:2]
        return f"{1e3 * total / calls:.1f} ms"

    def move_ms(backend, kind):
        return per_launch(blocks[backend], kind)

    def stack_ms(version, kind):
        return per_launch(stack[version], kind)

    step14 = (
        "**Host work off the GPU's path** (fourteenth step, H200 leases, `bash bench/gpu_issue48_step15.sh`): "
        "a mesh steps its set-up's boundary cells in by a compiled loop on threads (`queries.step_in`, the numbers of "
        "NumPy's loop to the bit), and numba-cuda copies into part of an array by one driver call. In turns, the "
        f"set-up took {in_turns(step_in, 'warp', 'setup')} on Warp and {in_turns(step_in, 'numba-cuda', 'setup')} on "
        "numba-cuda (the whole call "
        f"{in_turns(step_in, 'warp')} and {in_turns(step_in, 'numba-cuda')}); numba-cuda's rounds then took "
        f"{in_turns(copies, 'numba-cuda', 'rounds')}, the whole call {in_turns(copies, 'numba-cuda')}, the same "
        "spheres ([output](../bench/results/same_spheres_h200_issue48_step15b.txt); the device store's tests pass "
        "on the GPU: [output](../bench/results/gpu_tests_h200_issue48_step15b.txt)). numba-cuda's launches are "
        "replayed from their recorded arguments (the thirteenth step's branch, in turns with two others that did "
        "not pay: the history). The same move launches took Warp "
        f"{move_ms('warp', 'move_ids[move+ahead]')} and numba-cuda {move_ms('numba-cuda', 'move_ids[move+ahead]')} "
        f"each on the device in threads of their own, {move_ms('warp', 'move_ids[move+ahead] lanes')} and "
        f"{move_ms('numba-cuda', 'move_ids[move+ahead] lanes')} in cooperative blocks, whatever the block of the "
        "former (64, 128 or 256 threads: `--variants block-N`): Warp's code of the same walk is slower. Not for "
        "zeroing each walk's stack (a 64-int `vec_t`, zeroed at every call by a 256-byte loop of byte stores in the "
        "PTX): with `vec_t()` left unset (a patched copy of Warp; the same spheres: "
        "[output](../bench/results/stack_same_spheres_h200_issue48_step15.txt)) they took "
        f"{stack_ms('noinit', 'move_ids[move+ahead]')} against {stack_ms('installed', 'move_ids[move+ahead]')}, and "
        f"{stack_ms('noinit', 'move_ids[move+ahead] lanes')} against "
        f"{stack_ms('installed', 'move_ids[move+ahead] lanes')} cooperatively. Where "
        f"Warp's device still waits (a traced run of {seconds(waits15['wall_s'])}: busy "
        f"{seconds(waits15['device_busy_s'])}, idle {seconds(waits15['device_idle_s'])}): "
        + ", ".join(f"{step} {seconds(value)}" for step, value in list(waits15["idle_by_host_step_s"].items())[:6])
        + "; the final check's overlap search took "
        + ", ".join(f"{1e3 * pairs15[f'pairs_{threads}_threads_s']:.0f} ms" for threads in (1, 4, 8, 16))
        + " on 1, 4, 8 and 16 of the host's threads (`bench/verify_speed.py`): little gains past 8.")

    def fresh(backend):
        row = fresh16[backend]
        return f"{seconds(row['whole_s'])} (the first packing {seconds(row['first_packing_s'])})"

    step16 = (
        "**Sixteenth step** (one H200 lease, `bash bench/gpu_issue48_step16.sh inline` and `million`, main's code): "
        "Warp's functions printed `@wp.func(inline=True)` (46 calls in the move module's PTX become 5) made the "
        f"armadillo at 100,000 slower, {in_turns(inline, 'warp')} (the set-up "
        f"{in_turns(inline, 'warp', 'setup')}), with other spheres of the same volume "
        "([output](../bench/results/same_spheres_h200_issue48_step16b.txt)); the cube and the square at a million "
        f"the same spheres in {seconds(inline_1m[('cube', 'now')]['median'])} and "
        f"{seconds(inline_1m[('square', 'now')]['median'])} against {seconds(inline_1m[('cube', 'base')]['median'])} "
        f"and {seconds(inline_1m[('square', 'base')]['median'])}: kept aside (branch `issue48-step16-warp-inline`). "
        f"Warp's peak GPU memory at a million: the armadillo {int(peak16['armadillo']):,} MiB, the cube "
        f"{int(peak16['cube']):,} MiB ([output](../bench/results/memory_h200_issue48_step16.txt)). A fresh machine's "
        f"first packing of the armadillo, every cache empty (`bench/fresh_machine.py`): Warp {fresh('warp')}, "
        f"numba-cuda {fresh('numba-cuda')}, its GPU kernels' compile "
        f"{seconds(fresh16['warp']['compile_times']['warp'])} and "
        f"{seconds(fresh16['numba-cuda']['compile_times']['numba-cuda'])}.")
    step14_files = ["blocks_h200_warp_issue48_step15.json", "blocks_h200_numba-cuda_issue48_step15.json",
                    "armadillo_100k_h200_issue48_step15_turn1_base.json",
                    "armadillo_100k_h200_issue48_step15_turn2_base.json",
                    "armadillo_100k_h200_issue48_step15_turn1_now.json",
                    "armadillo_100k_h200_issue48_step15_turn2_now.json",
                    "stack_h200_warp_installed_issue48_step15.json", "stack_h200_warp_noinit_issue48_step15.json",
                    "armadillo_100k_h200_issue48_step15b_turn1_base.json",
                    "armadillo_100k_h200_issue48_step15b_turn2_base.json",
                    "armadillo_100k_h200_issue48_step15b_turn1_now.json",
                    "armadillo_100k_h200_issue48_step15b_turn2_now.json",
                    "armadillo_100k_h200_backends_issue48_step15b_now.json",
                    "armadillo_1m_h200_gpus_issue48_step15b_now.json",
                    "armadillo_1m_h200_numba_issue48_step15b_now.json",
                    "timeline_h200_warp_issue48_step15b_scale.json",
                    "verify_speed_h200_armadillo_100k_issue48_step15b.json"]
    step16_files = [*[f"{case}_1m_h200_backends_issue48_step16_base.json" for case in ("cube", "square")],
                    *[f"{case}_1m_h200_numba_issue48_step16_now.json" for case in ("cube", "square")],
                    "fresh_machine_h200_issue48_step16.json",
                    *[f"armadillo_100k_h200_warp_issue48_step16b_turn{turn}_base.json" for turn in (1, 2)],
                    *[f"{case}_1m_h200_backends_issue48_step16b_base.json" for case in ("cube", "square")],
                    *[f"armadillo_100k_h200_warp_issue48_step16b_turn{turn}_now.json" for turn in (1, 2)],
                    *[f"{case}_1m_h200_backends_issue48_step16b_now.json" for case in ("cube", "square")]]
    step7_files = ["profile_kernels_h100_armadillo_issue48_step7.json"]
    step7_files += ["work_model_2core_armadillo_100k_issue48_step7.json"]

    warp_10m = first(load("tiled_10M_h100_warp_alone.json")["rows"], run="alone")
    before = load("profile_kernels_h100_armadillo_issue48_before.json")["warp"]
    model7 = load("work_model_2core_armadillo_100k_issue48_step7.json")
    gpu = model7["against"]
    fill = {(row["shape"], row["run"]): row["fill"] for row in load("policy_fill_2core_10k.json")["rows"]}


    def now_1m(case, backend):
        return seconds(million16[case][backend]["median"])

    def parts(run):
        stages, device = run["stages"], run["device"]
        kernels = run["kernels"]
        moves = sum(entry[1] for name, entry in kernels.items() if name.startswith("move_ids"))
        return [stages["setup"], moves, device - moves, stages["rounds"] - device, stages["verify"], run["median"]]

    names = ["set-up", "move launches", "other launches", "host, in the rounds", "final check", "whole call"]
    arm7_profiled = load("profile_kernels_h100_armadillo_issue48_step7.json")["warp"]
    stages = ("setup", "moves", "other_launches", "host", "verify", "seconds")
    guess7 = [model7["prediction"][key] for key in stages]
    # The fourteenth step: a profiled H200 run of cf4f8d3's code, and the work model's prediction of it.
    model14 = load("work_model_2core_armadillo_100k_issue48_step14.json")
    arm14_profiled = load("stack_h200_warp_installed_issue48_step15.json")["warp"]
    guess14 = [model14["prediction"][key] for key in stages]
    split = [[name, seconds(old), seconds(new7), seconds(model7_), seconds(new14), seconds(model14_)]
             for name, old, new7, model7_, new14, model14_ in zip(names, parts(before), parts(arm7_profiled), guess7,
                                                                 parts(arm14_profiled), guess14)]
    rows = [
        ["armadillo (100k triangles)", "100,000", seconds(arm5["median"]), seconds(arm5_cuda["median"]),
         seconds(arm5_cpu["median"]), f"{arm5['fill']:.4f}", "medians of 3, cf4f8d3 (H200)"],
        ["unit cube", "100,000", *[seconds(median_of(cube, backend=b)) for b in ("warp", "numba-cuda", "numba")],
         f"{median_of(cube, 'fill', backend='warp'):.4f}", "medians of 2, 4ea141e"],
        ["armadillo (100k triangles)", "1,000,000", seconds(arm_1m["median"]), seconds(arm_1m_cuda["median"]),
         seconds(arm_1m_cpu["median"]), f"{arm_1m['fill']:.4f}", "medians of 2, cf4f8d3 (H200)"],
        *[[name, "1,000,000", now_1m(case, "warp"), now_1m(case, "numba-cuda"),
           seconds(million16_cpu[case]["median"]), f"{million16[case]['warp']['fill']:.4f}",
           "medians of 2, a1532dd (H200; numba: one run)"] for name, case in (("unit cube", "cube"),
                                                                            ("unit square", "square"))],
        ["unit cube", "10,000,000", seconds(warp_10m["seconds"]), "", "", f"{warp_10m['fill']:.4f}",
         "one run, e7f6fee"],
    ]
    head = ["shape", "spheres", "Warp, cuda:0", "numba-cuda", "numba, the host's 16 cores", "fill (Warp)", "runs, code"]
    cases = [("unit cube", "cube"), ("unit square", "square"), ("armadillo (20k triangles)", "armadillo")]
    policy = ", ".join(f"{short} {fill[(name, 'fast, GPU policies')] / fill[(name, 'faithful')]:.4f}"
                       for name, short in cases)
    return [
        "## Packing at scale: H100 (and H200)",
        "",
        "Fast mode, seed 0: seconds of the whole `nd.pack` call, the final float64 check included, the compile apart",
        "(a warm-up packing first). numba-cuda needs NumPy 2.4, carried to the GPU machine (its image's 2.5 breaks "
        "numba-cuda's CUDA target): it was not run from 3ffe337 to 9d800f2. The armadillo's rows are of one H200 lease "
        "(at 100,000 the three backends in one process; at a million the GPUs in one, numba in the next), the cube's "
        "and the square's at a million of another (the same way), the cube's at 100,000 and ten million of H100 "
        "leases.",
        "",
        *table(head, rows),
        f"Warp is {arm5_cpu['median'] / arm5['median']:.2f}x the host's 16 cores on the armadillo at "
        f"100,000 (numba-cuda {arm5_cpu['median'] / arm5_cuda['median']:.2f}x) and "
        f"{arm_1m_cpu['median'] / arm_1m['median']:.1f}x at a million (numba-cuda "
        f"{arm_1m_cpu['median'] / arm_1m_cuda['median']:.1f}x), "
        + ", ".join(f"{million16_cpu[case]['median'] / million16[case]['warp']['median']:.1f}x on the {case}"
                    for case in ("cube", "square"))
        + " at a million (goals: 5x; 1 s, 8 s, 5 s). "
        f"A GPU's fast mode fills at 10,000 spheres this fraction of the faithful mode's: {policy}.",
        "",
        "The armadillo at 100,000 by stage (each ends with a device sync) before issue 48, at its seventh step and at "
        "its fourteenth (the steps between: the history), and the work "
        "model's predictions from an earlier run's constants and the work counted on 2 cores "
        f"(`bench/work_model.py`; same launches: {'yes' if gpu['same_launches'] else 'no'}, "
        f"{'yes' if model14['against']['same_launches'] else 'no'}):",
        "",
        *table(["stage", "H100, before (e08d8b4)", "H100, the host's work (1e767cb)", "predicted (d7c0654's)",
                "H200, fourteenth step (cf4f8d3)", "predicted (1e767cb's)"], split),
        f"A move launch lasts as long as its slowest thread's chain ({1e6 * gpu['seconds_per_critical_node']:.2f} us a "
        f"node on the H100, {1e6 * model14['against']['seconds_per_critical_node']:.2f} us on the H200); the host's "
        f"round takes {gpu['host_over_cpu']:.1f}x and {model14['against']['host_over_cpu']:.2f}x its 2-core time. "
        "The final check finds overlaps in "
        "a grid's sorted rows (Numba), not k-d trees. Cells split finer (ratio 2.5, not 4) filled 0.5% more in 34 "
        "rounds, but took 2.72 s, not 2.07 s ([output](../bench/results/split_ratio_h100_issue48.txt)).",
        step14 + " " + step16,
        *sources(*step14_files, *step16_files,
                 *step7_files, "work_model_2core_armadillo_100k_issue48_step14.json",
                 "round_time_h100_cube_issue20_step7.json",
                 "tiled_10M_h100_warp_alone.json", "profile_kernels_h100_armadillo_issue48_before.json",
                 "policy_fill_2core_10k.json"),
    ]


def scale_2core() -> list[str]:
    arm = load("round_time_2core_issue20_step10.json")["results"]
    cube = [run for run in load("fast_tuning_2core_cube.json")["runs"] if run["variant"] == "now"]
    million = load("scale_million_2core.json")["runs"][0]
    nd = load("scale_nd_subdivided_2core.json")["runs"]
    rows = [
        ["armadillo (100k triangles)", "100,000", seconds(median_of(arm, version="now")),
         f"{median_of(arm, 'fill', version='now'):.4f}", "median of 3"],
        ["unit cube", "100,000", seconds(statistics.mean(run["seconds"] for run in cube)),
         f"{statistics.mean(run['fill'] for run in cube):.4f}", "mean of seeds 0 and 1"],
        ["unit cube", "1,000,000", seconds(million["seconds"]), f"{million['fill']['1000000']:.4f}", "one run"],
    ]
    for run in nd:
        spheres = count(run["spheres"]) if run["stop"] == "count" else f"{count(run['spheres'])} (time budget)"
        fill = run["fill"].get(str(run["spheres"]))
        rows.append([run["case"].replace("ball with a hole", "ball less a ball"), spheres, seconds(run["seconds"]),
                     f"{fill:.4f}" if fill else "", "one run"])
    return [
        "## Packing at scale: 2 cores",
        "",
        "Fast mode, numba on both cores, seed 0 unless said: seconds of the whole `nd.pack` call, compile apart.",
        "The 4-D to 6-D shapes are `Ball(0, 1) - Ball(0.3, 0.4)`; the subdivided armadillo has 400k triangles.",
        "",
        *table(["shape", "spheres", "seconds", "fill", ""], rows),
        *sources("round_time_2core_issue20_step10.json", "fast_tuning_2core_cube.json", "scale_million_2core.json",
                 "scale_nd_subdivided_2core.json"),
    ]


def auto_mode() -> list[str]:
    data = load("auto_mode_2core.json")
    counts = sorted({row["count"] for row in data["rows"]})
    shapes = list(dict.fromkeys((row["shape"], row["dim"]) for row in data["rows"]))
    rows = []
    for shape, dim in shapes:
        cells = []
        for n in counts:
            row = first(data["rows"], shape=shape, count=n)
            mark = "*" if row["auto"] == "fast" else ""
            cells.append(f"{row['fast_fill'] / row['faithful_fill']:.4f}{mark} "
                         f"({row['faithful_s']:.2f} / {row['fast_s']:.2f} s)")
        rows.append([shape, str(dim), *cells])
    return [
        "## Which mode `auto` takes",
        "",
        "The fast mode's fill over the faithful mode's at equal counts, and in brackets the seconds of each",
        f"(faithful / fast; medians of {data['repeats']}, seed 0, numba). `*`: `mode=\"auto\"` took the fast mode "
        f"there when measured (in {' and '.join(f'{d}-D' for d in data['auto_fast_dims'])}); 4-D: before issue 47's "
        "fast mode (next section), which `auto` now takes above 100 spheres in every dimension.",
        "",
        *table(["shape", "dim", *(f"{count(n)} spheres" for n in counts)], rows),
        *sources("auto_mode_2core.json"),
    ]


#: The fast mode's fill from 4-D up: the first file, then the rows run later (same spheres: the
#: code between changed speed only, bit for bit).
FAST_FILL = ("fast_fill_2core_issue47.json", "fast_fill_2core_issue47_10k.json")
FAST_FILL_SHAPES = ["ball with a hole", "simplex", "csg part", "periodic box, radii 0.03-0.2"]


def fast_high_dim() -> list[str]:
    every = [row for name in FAST_FILL for row in load(name)["rows"]]
    counts = sorted({row["count"] for row in every})
    found = {(row["shape"], row["dim"], row["count"], row["mode"]): row for row in every}
    rows = []
    for shape, dim in sorted(dict.fromkeys((row["shape"], row["dim"]) for row in every),
                             key=lambda key: (FAST_FILL_SHAPES.index(key[0]), key[1])):
        cells = []
        for n in counts:
            faithful, fast = found.get((shape, dim, n, "faithful")), found.get((shape, dim, n, "fast"))
            if faithful is None or fast is None:
                cells.append("")
                continue
            spread = max(faithful["spread"], fast["spread"])
            cells.append(f"{fast['mean_fill'] / faithful['mean_fill']:.4f} ({spread:.4f}, {len(fast['fills'])})")
        rows.append([shape, str(dim), *cells])
    return [
        "## The fast mode from 4-D up",
        "",
        "The fast mode's mean fill over the faithful mode's at equal counts (numba), with its narrower window and ties",
        "(`rounds.fast_window`, `_ties_first`); in brackets the seeds' spread ((max - min) / mean) and their number.",
        "",
        *table(["shape", "dim", *(f"{count(n)} spheres" for n in counts)], rows),
        *sources(*FAST_FILL),
    ]


def high_dim_speed() -> list[str]:
    data = load("index_speed_2core_issue47.json")
    rows = [[row["case"], seconds(row["before"]["median_s"]), seconds(row["after"]["median_s"]),
             f"{row['speedup']:.2f}x", "yes" if row["before"]["hashes"] == row["after"]["hashes"] else "no"]
            for row in data["rows"]]
    query_speedups = []
    for d in (3, 4, 5):
        biggest = max(load(f"index_queries_{d}d_2core_issue47.json")["rows"], key=lambda row: row["boxes"])
        query_speedups.append(f"{biggest['speedup']:.2f}x in {d}-D ({biggest['mean_row']:.0f} spheres a box)")
    gpu = load("index_speed_h100_warp_versions_issue47.json")
    host = load("index_speed_h100host_numba_issue47.json")
    gpu_rows = []
    for row in gpu["rows"]:
        numba = first(host["rows"], case=row["case"])["after"]
        gpu_rows.append([row["case"], *(f"{seconds(row[v]['median_s'])}, {row[v]['fill']:.4f}"
                                         for v in ("_v_f1ab864", "_v_f7731f1", "after")),
                         f"{seconds(numba['median_s'])}, {numba['fill']:.4f}"])
    return [
        "## 4-D and 5-D at scale: the sphere index",
        "",
        "The index's query skips the cells of its window out of reach (its corners: most of it from 4-D up), and a",
        "level holds spheres of a third to a sixth of its cells' side (`INDEX_FACTOR`). Same spheres, to the bit;",
        f"2 cores, numba, `mode=\"auto\"`, seed 0, medians of {len(data['rows'][0]['after']['seconds'])}, "
        "interleaved, every packing verified:",
        "",
        *table(["case", "before (`e557e8c~1`)", "now", "speedup", "same spheres"], rows),
        "The index alone, on a packing's own largest recorded query (median of 3): "
        f"{', '.join(query_speedups)}.",
        "",
        "H100, Warp, fast mode, one run each, seconds and fill: before issue 47 (`f1ab864`: window 0.2), with its "
        "narrower window (`f7731f1`), and now; the last column is numba on the same host's 16 cores, now. The "
        "narrower window fills 1.5-2.3% more but takes more rounds, each a set of launches: a cost the GPU "
        "pays (issue 48's subject).",
        "",
        *table(["case", "`f1ab864`", "`f7731f1`", "now", "numba, 16 cores"], gpu_rows),
        *sources("index_speed_2core_issue47.json", "index_queries_3d_2core_issue47.json",
                 "index_queries_4d_2core_issue47.json", "index_queries_5d_2core_issue47.json",
                 "index_speed_h100_warp_versions_issue47.json", "index_speed_h100host_numba_issue47.json"),
    ]


def shared_machine() -> list[str]:
    names = {"quiet": "threads_2core_quiet.json", "2 busy": "threads_2core_load2.json",
             "4 busy": "threads_2core_load4.json", "16 cores": "threads_h100host_issue47.json"}
    cases = list(dict.fromkeys(row["case"] for row in load(names["quiet"])["rows"]))
    rows = []
    for case in cases:
        cells = []
        for name in names.values():
            found = load(name)["rows"]
            before, after, one = (first(found, case=case, threads=t, version=v)["median_seconds"]
                                  for t, v in (("default", "before"), ("default", "after"), ("1", "after")))
            cells.append(f"{before:.2f} → {after:.2f} ({one:.2f})")
        rows.append([case, *cells])
    quiet = load("auto_mode_threads_quiet_2core_issue47.json")
    busy = load("auto_mode_threads_load2_2core_issue47.json")
    counts = sorted({row["count"] for row in quiet["rows"] if not row["shape"].startswith("quick start")})
    auto_rows = []
    for shape in dict.fromkeys(row["shape"] for row in quiet["rows"]):
        cells = []
        for n in counts:
            found = [row for row in quiet["rows"] if row["shape"] == shape and row["count"] == n]
            if not found:
                cells.append("")
                continue
            calm, loaded = found[0], first(busy["rows"], shape=shape, count=n)
            cells.append(f"{calm['auto_s']:.2f} → {loaded['auto_s']:.2f} ({loaded['auto_one_thread_s']:.2f})")
        if not any(cells):  # the quick start's example: its own count
            calm = first(quiet["rows"], shape=shape)
            loaded = first(busy["rows"], shape=shape)
            shape = f"{shape}, {count(calm['count'])}"
            cells = [f"{calm['auto_s']:.2f} → {loaded['auto_s']:.2f} ({loaded['auto_one_thread_s']:.2f})"] + [""] * (
                len(counts) - 1)
        auto_rows.append([shape, *cells])
    ratios = [first(busy["rows"], shape=row["shape"], count=row["count"])["auto_s"] / row["auto_s"]
              for row in quiet["rows"]]
    voxel = load("voxel_speed_2core_issue47.json")
    voxel_rows = [[("quiet" if row["load_processes"] == 0 else f"{row['load_processes']} busy"),
                   seconds(row["voxel_seconds"]), f"{row['default_threads_s']:.2f} s ({row['one_thread_s']:.2f} s)",
                   f"{row['default_threads_ratio']:.0f}x ({row['one_thread_ratio']:.0f}x)"] for row in voxel["rows"]]
    conflicts = load("conflicts_2core_issue47.json")
    periodic = {row["mode"]: row for row in conflicts["packings"] if row["case"] == "periodic-72"}
    return [
        "## Sharing a machine",
        "",
        "Numba's parallel launches go to all threads only where the threads would spare more than waking them",
        "costs (`NumbaBackend._run`). Seconds with the default threads, before → after that change, and on one",
        "thread in brackets (numba, seed 0, medians of 3, interleaved, fresh process a run; N busy: N spinning",
        "processes beside the runs on the 2 cores):",
        "",
        *table(["case", "2 cores, quiet", "2 busy", "4 busy", "16 cores (H100 host), quiet"], rows),
        "Every case of `bench/auto_mode.py` and the quick start's example, `mode=\"auto\"`: seconds quiet →",
        "beside 2 busy processes with the default threads, and (in brackets) busy on one thread. Busy over",
        f"quiet: {min(ratios):.2f}-{max(ratios):.2f}x.",
        "",
        *table(["case", *(f"{count(n)} spheres" for n in counts)], auto_rows),
        f"{count(voxel['count'])} spheres in the unit cube: SciPy's voxel method ({voxel['voxels']}^3 distance",
        "transform, `bench/scale.py`'s `voxel_greedy`) against ndpack, `mode=\"auto\"`, default threads (one",
        f"thread in brackets; medians of {voxel['repeats']}, one voxel run each):",
        "",
        *table(["machine", "voxels", "ndpack", "voxels / ndpack"], voxel_rows),
        "The periodic conflict check: 72 discs of radii 0.01-0.2 in a 2-D periodic box, fast mode",
        f"{periodic['fast']['seconds']:.2f} s against faithful {periodic['faithful']['seconds']:.2f} s (one run each).",
        "",
        *sources(*names.values(), "auto_mode_threads_quiet_2core_issue47.json",
                 "auto_mode_threads_load2_2core_issue47.json", "voxel_speed_2core_issue47.json",
                 "conflicts_2core_issue47.json"),
    ]


def compile_once() -> list[str]:
    user = load("compile_cache_2core_issue48_step12.json")
    before = {row["shape"]: row for row in load("compile_cache_2core_issue48_step12_base.json")["rows"]}
    rows = [[row["shape"], seconds(row["first"]["wall"]), seconds(row["warm"]["wall"]),
             seconds(before[row["shape"]]["first"]["wall"])] for row in user["rows"]]
    return [
        "## Compile once",
        "",
        "Whole `ndpack pack SPEC -n N --mode fast -q` processes, one after another, from an empty kernel cache: "
        "the first run of each shape, then a warm re-run of it. Kernels compile once per machine and kind; a "
        "new size, tree or mesh compiles nothing. One run each. Since issue 48's twelfth step the checks' grids "
        "compile in a helper process beside the packing's first compile (`ndpack.compile_ahead`); before it, a "
        "helper compiled the shape-free kernels, which cost more than it saved (the last column). Issue 19's "
        "table (the demo's first process 10.2 s then): [benchmarks-history.md](benchmarks-history.md).",
        "",
        f"2 cores, numba, {user['n']} spheres (the part is `Box(0, side) - Ball(side, 0.6 side)`):",
        "",
        *table(["shape", "first process", "warm re-run", "first process, 4d9dd08"], rows),
        *sources("compile_cache_2core_issue48_step12.json", "compile_cache_2core_issue48_step12_base.json"),
        *fresh_machine(),
    ]


#: A fresh machine's first packing (bench/fresh_machine.py): this code's files and the code before issue 48's
#: ninth step, measured in the same run.
FRESH = (("H100", "fresh_machine_h100_issue48_step12_turn1"), ("2 cores", "fresh_machine_2core_issue48_step12"))


def fresh_machine() -> list[str]:
    rows = []
    names = [f"{stem}_{version}.json" for _, stem in FRESH for version in ("base", "now")]
    for (machine, stem), version in ((place, version) for place in FRESH for version in ("base", "now")):
        name = f"{stem}_{version}.json"
        for row in load(name)["rows"]:
            titled = {title: value for title, value in row["compile_times"].items() if ":" in title}
            kernels = sum(value for title, value in titled.items() if not title.startswith("numba:"))
            rows.append([machine, f"`{row['backend']}`", f"`{SOURCES[name].commit}`", seconds(row["whole_s"]),
                         seconds(row["load_s"]), seconds(row["first_packing_s"]), seconds(row["next_packing_s"]),
                         seconds(sum(titled.values())), seconds(kernels) if kernels else ""])
    return [
        "A fresh machine's first packing of the armadillo (100k triangles, 3 spheres), every cache empty (ndpack's, "
        "Numba's, Warp's, the driver's): from `import ndpack` to the spheres (whole), loading the mesh (its tree and "
        "its queries' compile), the first `nd.pack`, a second in the same process; the compiles ndpack timed, all "
        "and the GPU kernels' (the rest are Numba's CPU compiles: the mesh queries and the checks' grids, "
        "which every backend waits for; a compile helper's time counts where the packing waited for it, the "
        "numba-cuda kernels', or where the helper took it, Numba's). At issue 48's twelfth step (19d892d) these "
        "compile in helper processes side by side (`ndpack.compile_ahead`, from 3 cores up), against 4d9dd08 in "
        "turns on one lease (the first turn; the second: \"Packing at scale: H100\"); on 2 cores (c9b18cc) one helper "
        "for the checks' grids. (The ninth step's table, before and after meshes had their own program: "
        "[benchmarks-history.md](benchmarks-history.md).)",
        "",
        *table(["machine", "backend", "code", "whole", "load", "first packing", "the next", "compiles",
                "of which GPU kernels"], rows),
        *sources(*names),
    ]


def tape() -> list[str]:
    names = ("tape_speed_2core_issue19.json", "tape_speed_h100_issue19.json")
    machines = {"tape_speed_2core_issue19.json": "2 cores", "tape_speed_h100_issue19.json": "H100"}
    rows = []
    for name in names:
        data = load(name)
        for backend in dict.fromkeys(row["backend"] for row in data["rows"]):
            cells = []
            for shape in ("demo", "deep", "mesh"):
                row = first(data["rows"], backend=backend, shape=shape)
                cells.append(f"{row['tape_pack_s'] / row['specialised_pack_s']:.2f} "
                             f"({row['tape_distances_per_s'] / row['specialised_distances_per_s']:.2f})")
            rows.append([f"`{backend}`, {machines[name]}", *cells])
    return [
        "## The tape against specialised code",
        "",
        "Built-in shapes run as data for one compiled interpreter (a tape); `NDPACK_KERNELS=specialised`",
        "compiles each tree as its own program. Packing time of the tape over the specialised program's",
        "(above 1: the tape is slower), and in brackets its distance rate over theirs (below 1: slower).",
        "Shapes: the demo part (3 leaves), a tree of 24 leaves nested four levels, the 20k-triangle armadillo.",
        "",
        *table(["backend, machine", "demo", "deep tree", "mesh"], rows),
        *sources(*names),
    ]


def mesh_queries() -> list[str]:
    gpu, cpu = load("mesh_queries_h200.json"), load("mesh_queries_2core.json")

    def rates(data):
        return {(mesh["mesh"], row["engine"], row["device"] != "cpu"): row["queries_per_s"]
                for mesh in data["meshes"] for row in mesh["rows"]}

    gpu_rates, cpu_rates = rates(gpu), rates(cpu)
    engines = list(dict.fromkeys((engine, on_gpu) for _, engine, on_gpu in [*gpu_rates, *cpu_rates]))
    meshes = [mesh["mesh"] for mesh in gpu["meshes"]]

    def rate(values, mesh, engine, on_gpu):
        value = values.get((mesh, engine, on_gpu))
        return "" if value is None else (f"{value / 1e6:.2f} M/s" if value >= 1e6 else f"{value / 1e3:.0f} k/s")

    engines = [(engine, on_gpu) for engine, on_gpu in engines if "(oracle)" not in engine]  # = the backend's
    rows = [[engine, "GPU" if on_gpu else "CPU",
             *(rate(gpu_rates, mesh, engine, on_gpu) for mesh in meshes),
             *(rate(cpu_rates, mesh, engine, on_gpu) for mesh in meshes)] for engine, on_gpu in engines]
    return [
        "## Mesh distance queries",
        "",
        f"Signed distances of {count(gpu['points'])} points (H200) and {count(cpu['points'])} (2 cores) in the "
        "armadillo's box, per engine: medians",
        f"of {gpu['repeats']} and {cpu['repeats']} repeats, copies to and from the GPU included. All agree with "
        "ndpack's float64 answer to",
        "float32 rounding or better but `wp.Mesh`'s own sign on the subdivided mesh.",
        "",
        *table(["engine", "device", *(f"H200 host and GPU, {m}" for m in meshes), *(f"2 cores, {m}" for m in meshes)],
               rows),
        *sources("mesh_queries_h200.json", "mesh_queries_2core.json"),
    ]


def fill_against_count() -> list[str]:
    fill = load("fill_vs_count.json")
    grids = {"square": "2-D, grid 181²", "square_fine": "2-D, grid 512²", "cube": "3-D, grid 32³"}
    rows = []
    for case in fill["cases"]:
        at = {row["count"]: row["fill"] for row in case["table"]}
        fit = case["fit"]
        rows.append([grids[case["name"]], f"{at[100]:.5f}", f"{at[1000]:.5f}",
                     f"{case['final']['fill']:.5f} at {count(case['final']['count'])}", f"{fit['exponent']:.3f}",
                     f"{fit['theory']:.3f}", " / ".join(f"{part['exponent']:.3f}" for part in case["local_exponents"])])
    return [
        "## Fill against count",
        "",
        "The faithful mode, one sphere a round (`batch=1`), seed 0, NumPy; the square a second time on a 512²",
        "grid. The exponent a of the uncovered fraction, `1 - fill ~ C N^-a`, fitted over N = 100 to the end,",
        "against Apollonian theory, and over 100-300 / 300-1,000 / 1,000-3,000 / 3,000-end: the 181² grid",
        "bends the 2-D slope once the gaps are smaller than its cells, the 512² grid keeps close to theory.",
        "",
        *table(["case", "fill at 100", "at 1,000", "at the end", "fitted a", "theory", "a over the sub-ranges"], rows),
        "![fill against count](img/fill_vs_count.png)",
        "",
        *sources("fill_vs_count.json"),
    ]


def pictures() -> list[str]:
    cpu, host = load("render_speed_2core.json"), load("render_speed_h100host.json")
    rows = []
    for run in cpu["runs"]:
        other = first(host["runs"], spheres=run["spheres"], view=run["view"])
        rows.append([count(run["spheres"]), f"{run['view'][0]:.0f}, {run['view'][1]:.0f}",
                     seconds(run["image_s"]), seconds(run["with_png_s"]),
                     seconds(other["image_s"]), seconds(other["with_png_s"])])
    size = "x".join(map(str, cpu["args"]["size"]))
    return [
        "## Pictures: the 3-D ray-caster",
        "",
        f"`ndpack.pictures.render` of a fast packing of {count(cpu['args']['base'])} spheres in the unit cube and of "
        f"ten copies of it side by side, at {size}",
        "(3x3 rays a pixel), medians after a compiling warm-up. It runs on the CPU.",
        "",
        *table(["spheres", "view (azimuth, elevation)", "2 cores: image", "and PNG file", "H100 host: image",
                "and PNG file"], rows),
        *sources("render_speed_2core.json", "render_speed_h100host.json"),
    ]


def beds() -> list[str]:
    cpu, gpu = load("dem_fill_2core_issue22b.json")["rows"], load("dem_fill_h100_issue22.json")["rows"]
    rows, spread = [], 0.0
    for row in cpu:
        same = [other for other in gpu if other["case"] == row["case"] and other.get("target") == row.get("target")]
        spread = max(spread, *(abs(other["solid_fraction"] / row["solid_fraction"] - 1) for other in same))
        times = [seconds(first(same, backend=b)["seconds"]) for b in ("numba", "warp", "numba-cuda")]
        case = "greedy driver (`pack`), the same count" if row["case"].startswith("greedy") else row["case"]
        rows.append([case, f"{row['target']:.2f}" if "target" in row else "", f"{row['solid_fraction']:.3f}",
                     count(row["count"]), f"{row['ks']:.4f}" if "ks" in row else "",
                     count(row["unplaced"]) if "unplaced" in row else "", seconds(row["seconds"]), *times])
    return [
        "## Granular beds",
        "",
        "The size-distribution driver (`pack_sizes`) in a cylinder (radius 0.5, height 1) and a periodic 4-D",
        "cell, equal spheres with walls and in periodic cells, and the greedy driver at the same count; each",
        "backend warmed up first. Fill, count, KS distance and spheres given up are numba's on 2 cores; the",
        f"other backends reach the same fills within {spread:.1%}.",
        "",
        *table(["case", "target", "reached", "spheres", "KS by mass", "given up", "2 cores", "H100 host, numba",
                "Warp", "numba-cuda"], rows),
        *sources("dem_fill_2core_issue22b.json", "dem_fill_h100_issue22.json"),
    ]


def dense_beds() -> list[str]:
    runs = load("dense_beds_2core_issue49.json")["rows"]
    rows = [[row["what"], f"{row['goal']:.3f}" if row["goal"] else "", f"{row['fill']:.4f}", count(row["spheres"]),
             seconds(row["seconds"]),
             f"{row['relaxations']} / {count(row['steps'])}",
             f"{row['contacts']['mean']:.2f} / {row['contacts']['backbone_mean']:.2f}",
             f"{row['ks_by_mass']:.4f}" if "ks_by_mass" in row else ""] for row in runs]
    return [
        "## Dense beds",
        "",
        "`nd.pack_dense` (issue 49): seed 0, numba on 2 cores, from the call to the verified bed (the contact kernels "
        "compiled apart). Goals: the issue's, from the literature's random close packing (jamming) fractions. "
        "Contacts: the mean a particle (walls count) and among the non-rattlers, gaps within 0.1% of the reach; "
        "KS by mass against the distribution scaled by the bed's factor.",
        "",
        *table(["case", "goal", "reached", "particles", "2 cores", "relaxations / FIRE steps", "contacts",
                "KS by mass"], rows),
        *sources("dense_beds_2core_issue49.json"),
    ]


def coverings() -> list[str]:
    counts = load("cover_2core.json")["rows"]
    times = load("cover_2core_times.json")["rows"]
    rows = []
    for row in times:
        mesh, tolerance = row["mesh"], row["tolerance"]
        ours = first(counts, kind="tolerance", mesh=mesh, tolerance=tolerance, method="ndpack")
        theirs = first(counts, kind="tolerance", mesh=mesh, tolerance=tolerance, method="k-means")
        k_means = count(theirs["spheres"]) if not theirs.get("cap_hit") else f"> {count(theirs['spheres'])}"
        rows.append([mesh, count(row["triangles"]), f"{tolerance:.1%}", count(ours["spheres"]), seconds(row["seconds"]),
                     k_means, f"{theirs['boundary_covered']:.1%} / {theirs['interior_covered']:.1%}"])
    repeats = load("cover_2core_times.json")["args"]["repeats"]
    return [
        "## Collision spheres: coverings against k-means",
        "",
        "Spheres to cover each mesh with a protrusion of at most the given share of its bounding-box diagonal:",
        "`nd.cover` beside k-means on surface samples (each cluster's sphere on its centroid, reaching its",
        "farthest sample; the fewest clusters within the protrusion, at most 20,000). Both are judged by",
        f"`nd.check_covering` on fresh samples. ndpack's time: median of {repeats} (mesh loading and compiling apart).",
        "",
        *table(["mesh", "triangles", "protrusion", "ndpack spheres", "ndpack time", "k-means spheres",
                "k-means covered (boundary / interior samples)"], rows),
        *sources("cover_2core.json", "cover_2core_times.json"),
    ]


def many_parts() -> list[str]:
    cpu, gpu = load("many_parts_2core.json"), load("many_parts_h100.json")
    workers = sorted({row["workers"] for row in cpu["rows"] + gpu["rows"]})
    rows = []
    for n in workers:
        cells = []
        for data in (cpu, gpu):
            row = next((row for row in data["rows"] if row["workers"] == n), None)
            cells.append(f"{seconds(row['seconds'])} ({row['parts_per_minute']:.0f} a minute)" if row else "")
        rows.append([str(n), *cells])
    return [
        "## Many parts: a local process pool",
        "",
        f"`nd.pack_many`, {count(cpu['count'])} spheres a part, numba, one run each after a run that compiled every "
        "kernel: on 2 cores",
        f"{len(cpu['sources'])} parts (three meshes, nine built-in shapes), on the H100 machine's 16 cores "
        f"{len(gpu['sources'])} built-in shapes (2-D to 4-D).",
        "",
        *table(["workers", "2 cores", "H100 host"], rows),
        *sources("many_parts_2core.json", "many_parts_h100.json"),
    ]


def tiles() -> list[str]:
    runs, alone = [], {}
    for name, label in (("tiled_1M_h100_numba.json", "H100 host, numba"), ("tiled_1M_h100_warp.json", "H100, Warp"),
                        ("tiled_10M_h100_warp_alone.json", "H100, Warp"), ("tiled_10M_h100_warp_8.json", "H100, Warp"),
                        ("tiled_10M_h100_warp_16.json", "H100, Warp"), ("tiled_2core.json", "2 cores, numba")):
        for row in load(name)["rows"]:
            if row["run"] == "alone":
                alone[label, row["spheres"]] = row["fill"]
            # The ten-million tiled runs were apart from their run alone (--no-alone): the ratio is to its file.
            ratio = row.get("fill_ratio") or (row["fill"] / alone[label, row["spheres"]] if "workers" in row else None)
            run = row["run"].replace("1 workers", "1 worker")
            if "workers" in row and "Warp" in label:
                run = run.replace("workers", "processes")
            runs.append([label, run, count(row["spheres"]), seconds(row["seconds"]), f"{row['fill']:.5f}",
                         f"{ratio:.4f}" if ratio else "",
                         f"{row['busy_share']:.2f}" if "busy_share" in row else "",
                         f"{row['halo_share']:.2f}" if "halo_share" in row else ""])
    mesh = load("tiled_mesh_2core.json")
    mesh_rows = [[row["run"].replace("1 workers", "1 worker"), seconds(row["seconds"]), f"{row['fill']:.4f}"]
                 for row in mesh["rows"]]
    return [
        "## One domain in tiles",
        "",
        "`nd.pack_tiled` (default tiles: 4 slabs a worker across x) against `nd.pack` alone on the same backend,",
        "the unit cube, seed 0, one run each; seconds of the whole call, the final check included. \"of alone\":",
        "the fill over the run alone's; \"busy\": the tiles' time over the workers times the phases' wall time;",
        "\"halo share\": the spheres made in a halo rather than in their own tile.",
        "",
        *table(["machine, backend", "run", "spheres", "seconds", "fill", "of alone", "busy", "halo share"], runs),
        f"A mesh in tiles (2 cores, numba, {mesh['mesh']}, {count(mesh['count'])} spheres): a tile packs "
        "`shape & Box(...)`, whose gradient",
        "is taken by differences, where a mesh alone has a closed form.",
        "",
        *table(["run", "seconds", "fill"], mesh_rows),
        *sources("tiled_1M_h100_numba.json", "tiled_1M_h100_warp.json", "tiled_10M_h100_warp_alone.json",
                 "tiled_10M_h100_warp_8.json", "tiled_10M_h100_warp_16.json", "tiled_2core.json",
                 "tiled_mesh_2core.json"),
    ]


SECTIONS = (intro, scale_h100, scale_2core, auto_mode, fast_high_dim, high_dim_speed,
            shared_machine, compile_once, tape,
            mesh_queries, fill_against_count, pictures, beds, dense_beds, coverings, many_parts, tiles)


def page() -> str:
    _cited.clear()
    rest = [line for section in SECTIONS[1:] for line in section()]
    lines = SECTIONS[0]() + rest
    while lines and not lines[-1]:
        lines.pop()
    return "\n".join(lines) + "\n"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default=str(PAGE), help="where to write the page ('-' prints it)")
    args = parser.parse_args(argv)
    text = page()
    if args.out == "-":
        sys.stdout.write(text)
    else:
        Path(args.out).write_text(text)
        print(f"{args.out}: {text.count(chr(10))} lines")


if __name__ == "__main__":
    main()
