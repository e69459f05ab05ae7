"""Compile ahead: kernels a packing will need, compiled by helper processes side by side.

A fresh machine's first packing compiles its kernels one after the other, as it first calls each:
on an H100's host numba-cuda's took 16.6 s, the mesh queries 7.3 s and the checks' grids 4.5 s of
a first packing of 40.9 s (``bench/fresh_machine.py``). Numba's compiler holds a lock for the whole
process, so threads cannot share the work, but processes can: a helper compiles what it is given
into Numba's disk cache, which hands the result over, and this process waits for a helper only
where it first needs one of its kernels (:func:`wait`), then loads it from disk. A fresh H100
machine's first packing of the armadillo took 21.5-24.2 s with numba-cuda against 29.8-38.5 s, and
17.1-17.4 s with Warp against 22.5-24.0 s; on 2 cores (one helper, for the checks' grids) 26.0 s
against 32.3 s with numba (issue 48, twelfth step; ``docs/benchmarks.md``, "Compile once").

A job is a function of an ndpack module and its arguments (JSON values), run in a helper as
``function(*arguments)``; :func:`start` shares the jobs out among helpers by their weights (the
heaviest first, each to the helper with the least so far), so that the helpers finish together.
A helper's failure costs only time: the kernels it did not leave on disk compile here.

``NDPACK_COMPILE_AHEAD=0`` turns helpers off (``1``: on whatever the cores); by default they run
where this process has a core to spare (see :func:`helpers_allowed`), at most :data:`HELPERS_MOST`
at once.
"""

from __future__ import annotations

import atexit
import heapq
import importlib
import json
import os
import subprocess
import sys
import time

from . import log

#: Helpers running at once, at most (a numba-cuda helper holds a CUDA context, hundreds of MiB).
HELPERS_MOST = 8
#: A helper waited for longer than this is killed, and its kernels compile here.
PATIENCE = 900.0

_helpers: dict[str, subprocess.Popen] = {}  # job key -> the helper running it
#: A helper's program: its jobs come as its first argument.
HELPER = "import sys; from ndpack.compile_ahead import main; main(sys.argv[1:])"


def helpers_allowed(least: int = 1) -> int:
    """How many helpers a batch may start now: the cores this process may use less one, at most
    :data:`HELPERS_MOST` less those running, and 0 below ``least`` (a batch that only pays when
    split) or where ``NDPACK_COMPILE_AHEAD=0``; with ``NDPACK_COMPILE_AHEAD=1`` at least ``least``.
    The cores this process may use are those it may run on, or its ``NUMBA_NUM_THREADS`` where
    that is fewer: a worker of ndpack's local pools has its share of the machine there, so that a
    pool on a fresh machine does not start a set of helpers in each worker."""
    setting = os.environ.get("NDPACK_COMPILE_AHEAD", "").strip()
    if setting == "0":
        return 0
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    threads = os.environ.get("NUMBA_NUM_THREADS", "").strip()
    if threads.isdigit() and int(threads) > 0:
        cores = min(cores, int(threads))
    running = sum(1 for helper in set(_helpers.values()) if helper.poll() is None)
    allowed = min(cores - 1, HELPERS_MOST) - running
    if setting == "1":
        allowed = max(allowed, least)
    return allowed if allowed >= least else 0


def share(jobs: list[tuple[str, float, str, list]], helpers: int) -> list[list[tuple[str, float, str, list]]]:
    """``jobs`` (key, weight, function, arguments) shared among at most ``helpers`` groups: the
    heaviest first, each to the group with the least weight so far (ties: the first such group)."""
    groups: list[list] = [[] for _ in range(max(1, min(helpers, len(jobs))))]
    loads = [(0.0, k) for k in range(len(groups))]
    for job in sorted(jobs, key=lambda job: -job[1]):
        load, k = heapq.heappop(loads)
        groups[k].append(job)
        heapq.heappush(loads, (load + job[1], k))
    return [group for group in groups if group]


def start(jobs: list[tuple[str, float, str, list]], least: int = 1) -> bool:
    """Run ``jobs`` (key, weight, ``"module:function"``, arguments) in helper processes, unless
    fewer than ``least`` may start (see :func:`helpers_allowed`) or a job of the same key is
    already under way. Returns whether helpers were started (where some could not be, the jobs
    they would have run are not under way: their kernels compile here)."""
    jobs = [job for job in jobs if job[0] not in _helpers]
    allowed = helpers_allowed(least)
    if not jobs or not allowed:
        return False
    started = False
    for group in share(jobs, allowed):
        calls = [[function, arguments] for _, _, function, arguments in group]
        try:
            helper = subprocess.Popen([sys.executable, "-c", HELPER, json.dumps(calls)], stdin=subprocess.DEVNULL,
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        except OSError:  # no more helpers here: this process compiles the rest when it first uses them
            break
        for key, _, _, _ in group:
            _helpers[key] = helper
        started = True
    return started


def wait(key: str) -> float:
    """Wait for the helper running job ``key``, if one is; returns the seconds waited (0 if none)."""
    helper = _helpers.pop(key, None)
    if helper is None:
        return 0.0
    started = time.perf_counter()
    try:
        code = helper.wait(timeout=PATIENCE)
    except subprocess.TimeoutExpired:  # compile here then; Numba never leaves half-written cache entries
        helper.kill()
        code = "killed"
    if code != 0:
        log.logger.debug(f"a compile helper for {key} ended with {code}: what it did not leave on disk compiles here")
    return time.perf_counter() - started


def _stop_helpers() -> None:
    """At exit, stop the helpers still running: this process never needed what they compile (it
    waits for what it needs), and a helper left running would write into a cache folder that may
    be removed next (a temporary one). Numba writes each cache entry whole, or not at all."""
    for helper in set(_helpers.values()):
        if helper.poll() is None:
            helper.kill()
            helper.wait()
    _helpers.clear()


atexit.register(_stop_helpers)


def under_way() -> list[str]:
    """The keys of the jobs whose helpers have not been waited for."""
    return sorted(_helpers)


def compile_signature(module: str, getter: str, name: str | None, signature: str) -> None:
    """A helper's job: the Numba function ``getter()`` of ndpack's ``module`` (``getter()[name]``
    where ``name`` is given) compiled for ``signature`` (Numba's words, as ``"(int64, float64[::1])"``)
    into the disk cache, as ``cache=True`` keeps it."""
    from numba.core import sigutils

    if not module.startswith("ndpack."):
        raise ValueError(f"a compile helper compiles ndpack's functions only, not {module!r}")
    function = getattr(importlib.import_module(module), getter)()
    if name is not None:
        function = function[name]
    arguments, _ = sigutils.normalize_signature(signature)
    function.compile(arguments)


def on_disk(dispatcher) -> bool:
    """Whether Numba's disk cache holds compiled code of ``dispatcher`` (unknown: True)."""
    index = getattr(getattr(getattr(dispatcher, "_cache", None), "_cache_file", None), "_index_path", None)
    return index is None or os.path.exists(index)


def function_on_disk(function) -> bool:
    """Whether Numba's disk cache holds compiled code of the plain ``function`` (as ``numba.njit(cache=True)``
    keeps it): nothing is compiled to know. A yes is kept for the process (asking costs 0.25 ms, which
    every packing would pay)."""
    if function in _on_disk:
        return True
    import numba

    found = on_disk(numba.njit(cache=True)(function))
    if found:
        _on_disk.add(function)
    return found


_on_disk: set = set()  # plain functions known to be in Numba's disk cache


def job_unless_on_disk(function, key: str, weight: float, call: str, arguments: list) -> list:
    """``[(key, weight, call, arguments)]``, a job for :func:`start`, where Numba's disk cache
    lacks the plain ``function`` the job compiles (:func:`function_on_disk`); else ``[]``."""
    return [] if function_on_disk(function) else [(key, weight, call, arguments)]


def main(argv: list[str]) -> None:
    """A helper: run each ``[function, arguments]`` of the JSON list ``argv[0]`` in turn."""
    for function, arguments in json.loads(argv[0]):
        module, name = function.split(":")
        if not module.startswith("ndpack."):
            raise SystemExit(f"a compile helper runs ndpack's functions only, not {function!r}")
        getattr(importlib.import_module(module), name)(*arguments)

