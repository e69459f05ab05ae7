"""Compiled loops run in slices by threads (ndpack.parallel), in place of Numba's parallel loops."""

from __future__ import annotations

import multiprocessing
import os

import numba
import numpy as np
import pytest

from ndpack.parallel import run_in_slices


@numba.njit(nogil=True)
def count_visits(first, last, visits, slices):
    for i in range(first, last):
        visits[i] += 1
    slices[first] = last - first


@pytest.mark.parametrize("count", [0, 1, 7, 1000])
def test_every_item_once_in_slices(count):
    visits, slices = np.zeros(count, dtype=np.int64), np.zeros(max(count, 1), dtype=np.int64)
    run_in_slices(count_visits, count, visits, slices, slices_per_thread=4)
    assert (visits == 1).all()
    expected = 1 if count < 2 or numba.get_num_threads() < 2 else min(count, 4 * numba.get_num_threads())
    assert np.count_nonzero(slices) == (expected if count else 0)


def test_few_items_run_on_this_thread():
    visits, slices = np.zeros(50, dtype=np.int64), np.zeros(50, dtype=np.int64)
    run_in_slices(count_visits, 50, visits, slices, serial_below=100)
    assert (visits == 1).all() and slices[0] == 50 and np.count_nonzero(slices) == 1


def test_an_error_in_a_slice_is_raised_here():
    def failing(first, last):
        if first > 0:
            raise ValueError(f"slice from {first}")

    if numba.get_num_threads() < 2:
        pytest.skip("one thread: one call")
    with pytest.raises(ValueError, match="slice from"):
        run_in_slices(failing, 100)


def _in_child(queue, parents_pool):
    # The pool this process would use, asked before any slice runs: were it the parent's (inherited by
    # fork, without its threads), running slices in it would wait forever, so the child says so instead.
    import numba

    from ndpack import parallel

    fresh = parallel._pool(numba.get_num_threads(), os.getpid()) is not parents_pool
    visits, slices = np.zeros(500, dtype=np.int64), np.zeros(500, dtype=np.int64)
    if fresh:
        run_in_slices(count_visits, 500, visits, slices)
    queue.put((fresh, int(visits.sum())))


def test_a_forked_child_gets_its_own_threads():
    """A child made by fork inherits the parent's pool, not its threads: it must not wait for them."""
    if "fork" not in multiprocessing.get_all_start_methods():
        pytest.skip("no fork here")
    from ndpack import parallel

    run_in_slices(count_visits, 500, np.zeros(500, dtype=np.int64), np.zeros(500, dtype=np.int64))  # the pool
    parents_pool = parallel._pool(numba.get_num_threads(), os.getpid())
    context = multiprocessing.get_context("fork")
    queue = context.Queue()
    child = context.Process(target=_in_child, args=(queue, parents_pool))
    child.start()
    fresh, visited = queue.get()
    child.join()
    assert child.exitcode == 0 and fresh, "the forked child would have used the parent's pool"
    assert visited == 500
