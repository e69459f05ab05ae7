"""Launches sized to the work (issue 47): the numba backend runs a launch over a few items on one
thread, without waking Numba's thread pool, and a large one on all its threads; both give the
same bits. Where waking the threads costs more (measured: a busy machine), fewer launches use them.

No speed is asserted here (bench/threads.py measures it, quiet and busy).
"""

from __future__ import annotations

import numba
import numpy as np
import pytest

import ndpack as nd
from ndpack.backends import numba_backend
from ndpack.backends.numba_backend import NumbaBackend


def _pack(monkeypatch, parallel_from, shape, **options):
    """A packing on a fresh numba backend with a fixed threshold, and every launch it made."""
    monkeypatch.setattr(numba_backend, "PARALLEL_FROM", parallel_from)
    monkeypatch.setattr(numba_backend, "trace", [])
    packing = nd.pack(shape, backend=NumbaBackend(), seed=0, progress=False, **options)
    return packing, numba_backend.trace


@pytest.mark.parametrize("mode, count", [("faithful", 40), ("fast", 300)])
def test_serial_and_parallel_launches_pack_the_same_spheres(monkeypatch, mode, count):
    shape = nd.Box([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]) - nd.Ball([1.0, 1.0, 1.0], 0.6)
    options = {"n": count, "mode": mode, "grid": 12}
    parallel, on_threads = _pack(monkeypatch, 0.0, shape, **options)  # every launch on all threads
    serial, in_line = _pack(monkeypatch, float("inf"), shape, **options)  # every launch on one
    one = numba.get_num_threads() == 1  # then every launch is on one thread anyway
    assert on_threads and all(entry[3] is one for entry in on_threads)
    assert in_line and all(entry[3] for entry in in_line)
    np.testing.assert_array_equal(parallel.centers, serial.centers)
    np.testing.assert_array_equal(parallel.radii, serial.radii)
    assert serial.verify().ok


def _converge(backend, count, steps):
    """One converge launch of ``count`` prototypes of the unit 3-cube among 50 spheres."""
    rng = np.random.default_rng(1)
    shape = nd.Box([0.0, 0.0, 0.0], [1.0, 1.0, 1.0])
    points = rng.random((count, 3))
    centers, radii = rng.random((50, 3)), np.full(50, 0.01)
    neighbours = np.tile(np.arange(50), (count, 1))
    return backend.converge(shape, points, points - 0.05, points + 0.05, centers, radii, neighbours,
                            np.full(steps, 0.1))


def _busy(monkeypatch, backend, overhead=1e-3):
    """``backend`` measuring ``overhead`` seconds for a launch on all threads (a busy machine's)."""
    monkeypatch.setattr(numba_backend, "PARALLEL_FROM", None)
    monkeypatch.setattr(backend, "_probe", lambda dim, threads: overhead)
    return backend


def test_few_items_run_serially_and_many_on_the_threads(monkeypatch):
    monkeypatch.setattr(numba_backend, "trace", [])
    backend = _busy(monkeypatch, NumbaBackend())
    _converge(backend, 4, 10)
    assert numba_backend.trace[-1][:4] == ("converge_all", 4, 4 * 11 * (50 + numba_backend.SHAPE_UNITS), True)
    # A launch estimated at a second of work goes to the threads (where there are several).
    count = 200
    units = count * 51 * (50 + numba_backend.SHAPE_UNITS)
    monkeypatch.setitem(backend._rates, id(backend._kernels(nd.Box([0.0] * 3, [1.0] * 3))[0]["converge_all"]),
                        1.0 / units)  # whatever the overhead measured
    _converge(backend, count, 50)
    assert numba_backend.trace[-1][3] is (numba.get_num_threads() == 1)
    # One thread (the option, or NUMBA_NUM_THREADS=1): always one.
    single = NumbaBackend(threads=1)
    monkeypatch.setattr(single, "_rates", backend._rates)
    _converge(single, count, 50)
    assert numba_backend.trace[-1][3] is True
    # PARALLEL_FROM = 0: every launch on the threads, as before issue 47.
    monkeypatch.setattr(numba_backend, "PARALLEL_FROM", 0.0)
    _converge(backend, 4, 10)
    assert numba_backend.trace[-1][3] is (numba.get_num_threads() == 1)


@pytest.mark.skipif(numba.get_num_threads() == 1, reason="one Numba thread: every launch is on one")
def test_the_threshold_follows_the_measured_overhead_of_the_threads(monkeypatch):
    monkeypatch.setattr(numba_backend, "PARALLEL_FROM", None)
    seen = []

    def entry(*args):  # stands for a compiled entry: which thread count it ran under
        seen.append(numba.get_num_threads())

    backend = NumbaBackend()
    overhead = [5e-6]  # a quiet machine's: microseconds
    monkeypatch.setattr(backend, "_probe", lambda dim, threads: overhead[0])
    namespace, points = {"touched_all": entry}, np.zeros((4, 3))
    units = int(1e-3 / numba_backend.RATES["touched_all"])  # a millisecond on one thread
    backend._run(namespace, "touched_all", units, points)
    assert seen[-1] > 1
    # Busy: waking the threads costs milliseconds. Measured again after PROBE_EVERY seconds
    # (here at once), and the median of the last PROBES probes counts.
    monkeypatch.setattr(numba_backend, "PROBE_EVERY", 0.0)
    overhead[0] = 5e-3
    for _ in range(numba_backend.PROBES):
        backend._run(namespace, "touched_all", units, points)
    assert seen[-1] == 1
    backend._run(namespace, "touched_all", 1000 * units, points)  # a second of work still pays
    assert seen[-1] > 1
    # Under PARALLEL_MIN seconds of work, never measured at all: one thread.
    backend._run(namespace, "touched_all", 1, points)
    assert seen[-1] == 1


def test_the_threshold_weighs_work_not_items(monkeypatch):
    # Thousands of prototypes against one new sphere is little work: serial, and the same answer.
    monkeypatch.setattr(numba_backend, "trace", [])
    backend = _busy(monkeypatch, NumbaBackend(), overhead=1e-4)
    rng = np.random.default_rng(2)
    points, clearance = rng.random((5000, 3)), np.full(5000, 0.05)
    center, radius = rng.random((1, 3)), np.full(1, 0.1)
    touched = backend.touched(points, clearance, center, radius)
    assert numba_backend.trace[-1][:4] == ("touched_all", 5000, 10000, True)
    monkeypatch.setattr(numba_backend, "PARALLEL_FROM", 0.0)
    np.testing.assert_array_equal(touched, backend.touched(points, clearance, center, radius))
    assert numba_backend.trace[-1][3] is (numba.get_num_threads() == 1)
    assert (touched == 0).any() and (touched == -1).any()


def test_a_launch_on_one_thread_moves_its_rate_by_a_bounded_step(monkeypatch):
    monkeypatch.setattr(numba_backend, "LEARN_FROM", 0.0)
    monkeypatch.setattr(numba_backend, "PARALLEL_FROM", float("inf"))
    backend = NumbaBackend()
    _converge(backend, 30, 20)
    key = id(backend._kernels(nd.Box([0.0] * 3, [1.0] * 3))[0]["converge_all"])
    first = backend._rates[key]
    assert 0 < first <= numba_backend.RATES["converge_all"] * 2.0 ** 0.2
    monkeypatch.setitem(backend._rates, key, 1e-15)  # far too cheap: a launch raises it by a bounded step
    _converge(backend, 30, 20)
    assert backend._rates[key] == pytest.approx(1e-15 * 2.0 ** 0.2)


def test_a_small_launch_runs_on_one_thread_and_a_large_one_on_all(monkeypatch):
    monkeypatch.setattr(numba_backend, "PARALLEL_FROM", None)
    # A fixed, quiet overhead: the decision, not this machine's scheduler, is under test.
    monkeypatch.setattr(NumbaBackend, "_probe", lambda self, dim, threads: 5e-6)
    seen = []

    def entry(*args):  # stands for a compiled entry: which thread count it ran under
        seen.append(numba.get_num_threads())

    everyone = numba.get_num_threads()
    namespace = {"touched_all": entry}
    points = np.zeros((4, 3))
    NumbaBackend()._run(namespace, "touched_all", 10, points)  # under PARALLEL_MIN
    NumbaBackend()._run(namespace, "touched_all", 10**9, points)  # seconds of work
    NumbaBackend(threads=1)._run(namespace, "touched_all", 10**9, points)
    assert seen == [1, everyone, 1]
    assert numba.get_num_threads() == everyone  # given back
