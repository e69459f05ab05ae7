"""Where independent tasks run: this process, a local pool of processes, or a Dask cluster.

:func:`ndpack.pack_many` runs one task per part, and :func:`ndpack.pack_tiled` a batch of tile
tasks per phase, through the same :class:`Workers`::

    with Workers(workers=4, shared=shape) as pool:
        for key, result, error in pool.run(function, {key: task, ...}):
            ...  # function(shape, task) ran somewhere; error is None or the exception

A local pool starts its processes by ``spawn`` (numba and ``fork`` do not mix), which imports the
calling script again in each worker: a script calls it under ``if __name__ == "__main__":``, as
any process pool or Dask ``LocalCluster`` needs. ``shared`` (a shape, say) travels to each worker
once, not with every task: by the pool's initializer, or ``client.scatter(broadcast=True)``.
Nothing imports Dask unless a client is given.
"""

from __future__ import annotations

import os
import signal

from ..errors import ParameterError

#: What a pool worker was given once (``Workers(shared=...)``), for every task it runs.
_SHARED = None


class Workers:
    """A place to run batches of independent tasks, opened once for many batches.

    Parameters
    ----------
    workers : int, optional
        Local processes (default ``os.cpu_count()``); 1 runs the tasks here, one by one, with no
        pool. Ignored with ``client``.
    client : dask.distributed.Client, optional
        Run the tasks on this Dask cluster (``client.submit``).
    shared : object, optional
        Passed as the first argument of every task's function; sent to each worker once.
    most : int, optional
        No more local processes than this (the number of tasks there will be, so that none idles).
    gpus : sequence of int, optional
        Spread the local processes over these GPUs, in turn: each sees one of them, as ``cuda:0``
        (``CUDA_VISIBLE_DEVICES``), as dask-cuda gives each of its workers one GPU.
    """

    def __init__(self, workers: int | None = None, client=None, shared=None, most: int | None = None,
                 gpus=None):
        if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
            raise ParameterError(f"workers must be a positive integer, got {workers!r}")
        if gpus is not None:
            gpus = list(gpus)
            if not gpus or not all(isinstance(g, int) and not isinstance(g, bool) and g >= 0 for g in gpus):
                raise ParameterError(f"gpus must be GPU numbers (integers >= 0), such as [0, 1], got {gpus!r}")
            if client is not None:
                raise ParameterError("gpus= spreads local processes over GPUs; on Dask, start a worker per GPU "
                                     "(dask-cuda's LocalCUDACluster) instead")
        self.client, self.shared = client, shared
        most = 1 << 30 if most is None else most  # no tasks (all done before): no pool to start
        self.processes = 1 if client is not None else max(1, min(workers or os.cpu_count() or 1, most))
        self._pool = self._shared_future = None
        self._futures = []  # the last Dask batch's, for stop()
        if client is not None and shared is not None:
            self._shared_future = client.scatter(shared, broadcast=True)
        elif self.processes > 1 or gpus:
            self._pool = _start_pool(self.processes, shared, gpus)

    @property
    def count(self) -> int:
        """How many tasks run at once: the local processes, or the Dask cluster's worker threads."""
        if self.client is not None:
            return max(1, sum(self.client.nthreads().values()))
        return self.processes

    def run(self, function, tasks: dict):
        """Run ``function(shared, task)`` for each of ``tasks`` (a dict of key to task); yields
        ``(key, result, error)`` as each finishes (``error`` is None, or the exception it raised;
        a worker that died is reported as an error of its tasks). ``function`` must be a
        module-level function (it is pickled to the workers)."""
        if self.client is not None:
            yield from self._run_dask(function, tasks)
        elif self._pool is None:
            for key, task in tasks.items():
                try:
                    result, error = function(self.shared, task), None
                except Exception as caught:  # noqa: BLE001 - one task's failure, reported to the caller
                    result, error = None, caught
                yield key, result, error
        else:
            yield from self._run_pool(function, tasks)

    def _run_pool(self, function, tasks: dict):
        from concurrent.futures import as_completed
        from concurrent.futures.process import BrokenProcessPool

        futures = {self._pool.submit(_call, function, task): key for key, task in tasks.items()}
        for future in as_completed(futures):
            try:
                result, error = future.result(), None
            except BrokenProcessPool as broken:
                result, error = None, BrokenProcessPool(
                    f"a worker process died ({broken}); in a script, call this under "
                    f"`if __name__ == \"__main__\":` (the workers import it again), or pass workers=1")
            except Exception as caught:  # noqa: BLE001 - the task's own error, or a result that could not travel
                result, error = None, caught
            yield futures[future], result, error

    def _run_dask(self, function, tasks: dict):
        from distributed import as_completed

        shared = self._shared_future if self._shared_future is not None else self.shared
        futures = {self.client.submit(function, shared, task, pure=False): key for key, task in tasks.items()}
        self._futures = list(futures)
        for future in as_completed(futures):
            try:
                result, error = future.result(), None
            except Exception as caught:  # noqa: BLE001 - a task's error, a worker lost, a result that failed to travel
                result, error = None, caught
            yield futures[future], result, error

    def close(self) -> None:
        """Let the pool's processes finish and end (nothing to do for Dask or this process)."""
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None

    def stop(self) -> None:
        """Stop now (Ctrl-C): drop the tasks not started and end the local workers; on Dask,
        cancel the last batch's tasks."""
        if self._pool is not None:
            # No public way to end the workers before Python 3.14; taken before shutdown, which forgets them.
            processes = list((getattr(self._pool, "_processes", None) or {}).values())
            self._pool.shutdown(wait=False, cancel_futures=True)
            for process in processes:
                process.terminate()
            for process in processes:
                process.join(5)
            self._pool = None
        elif self.client is not None and self._futures:
            self.client.cancel(self._futures)

    def __enter__(self) -> Workers:
        return self

    def __exit__(self, kind, error, traceback) -> None:
        if kind is KeyboardInterrupt:
            self.stop()
        else:
            self.close()


def _start_pool(processes: int, shared, gpus=None):
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    context = multiprocessing.get_context("spawn")
    threads = max(1, (os.cpu_count() or 1) // processes)
    started = context.Value("i", 0)  # which worker this is, for its GPU
    return ProcessPoolExecutor(processes, mp_context=context, initializer=_start_worker,
                               initargs=(threads, shared, gpus, started))


def _start_worker(threads: int, shared, gpus=None, started=None) -> None:
    """A pool worker keeps what is shared, leaves Ctrl-C to the caller, which stops the pool (no
    traceback per worker), takes its share of the cores for Numba's parallel loops (``workers``
    processes of a thread per core each would oversubscribe the machine ``workers`` times; a
    ``NUMBA_NUM_THREADS`` set by the user is kept) and, with ``gpus``, the next GPU in turn as
    its only one (set before anything in it starts CUDA)."""
    global _SHARED
    _SHARED = shared
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    os.environ.setdefault("NUMBA_NUM_THREADS", str(threads))  # read when numba is first imported: later
    if gpus:
        with started.get_lock():
            turn = started.value
            started.value += 1
        os.environ["CUDA_VISIBLE_DEVICES"] = str(gpus[turn % len(gpus)])


def _call(function, task):
    """A task in a pool worker: ``function(shared, task)``."""
    return function(_SHARED, task)
