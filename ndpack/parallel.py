"""Compiled loops run in slices by a pool of threads, in place of Numba's parallel loops.

A function compiled by Numba with ``nogil=True`` that loops over ``range(first, last)`` releases
the GIL while it runs, so Python threads run slices of one loop at once. Numba's parallel loops
(``prange``) do the same in Numba's thread pool, but each compiles about 1.5 s longer (the overlap
check's scan: 3.8 s against 2.3 s on 2 cores), and a loop also wanted on one thread for few items
is a second function to compile: a fresh machine's first packing waited for both, once.
"""

from __future__ import annotations

import functools
import os
from concurrent.futures import ThreadPoolExecutor


def run_in_slices(function, count: int, *args, serial_below: int = 2, slices_per_thread: int = 4) -> None:
    """Run ``function(first, last, *args)`` over ``range(count)`` in slices on Numba's thread
    count (``numba.get_num_threads()``, which ``NUMBA_NUM_THREADS`` and ``numba.set_num_threads``
    set), ``slices_per_thread`` slices a thread handed out as threads free up (items of unequal
    cost even out); below ``serial_below`` items, or with one thread, one call on this thread.

    ``function`` must release the GIL (Numba's ``nogil=True``) and write only its own items'
    outputs. An exception in a slice is raised here.
    """
    import numba

    threads = numba.get_num_threads()
    if count < max(serial_below, 2) or threads < 2:
        function(0, count, *args)
        return
    slices = min(count, threads * slices_per_thread)
    edges = [count * k // slices for k in range(slices + 1)]
    for _ in _pool(threads, os.getpid()).map(lambda k: function(edges[k], edges[k + 1], *args), range(slices)):
        pass


@functools.cache
def _pool(threads: int, process: int) -> ThreadPoolExecutor:
    """A pool of ``threads`` threads, kept (starting one cost about a millisecond a call); one per
    ``process``, as a child made by fork inherits the pool but not its threads."""
    return ThreadPoolExecutor(max_workers=threads, thread_name_prefix="ndpack")
