"""Where tasks run (``ndpack.scale.workers``): this process, a local pool, GPUs spread over its workers.

The pools and Dask are exercised through ``pack_many`` (tests/scale/test_many.py) and ``pack_tiled``
(tests/scale/test_tiled.py); here, what they do not show.
"""

import pytest

from ndpack.errors import ParameterError
from ndpack.scale.workers import Workers


def _visible_gpu(_shared, _task):
    import os
    import time

    time.sleep(0.2)  # long enough that each worker takes a task
    return os.environ.get("CUDA_VISIBLE_DEVICES")


def test_local_workers_are_spread_over_the_gpus_given():
    with Workers(2, gpus=[3, 5]) as pool:
        seen = {result for _, result, error in pool.run(_visible_gpu, dict.fromkeys(range(6))) if error is None}
    assert seen == {"3", "5"}
    with pytest.raises(ParameterError, match="gpus must be GPU numbers"):
        Workers(2, gpus=["0"])


def _double(shared, task):
    return shared * task


def test_no_tasks_start_no_pool_and_one_worker_runs_here():
    assert Workers(4, most=0)._pool is None  # a re-run whose parts are all done starts nothing
    with Workers(1, shared=3) as here:
        assert here._pool is None
        assert sorted(result for _, result, _ in here.run(_double, {0: 1, 1: 2})) == [3, 6]


def test_a_task_that_fails_is_reported_with_its_key_and_the_others_finish():
    with Workers(1, shared=None) as here:
        results = {key: (result, error) for key, result, error in here.run(_double, {"a": 2, "b": 3})}
    assert results["a"][0] is None and isinstance(results["a"][1], TypeError)  # None * 2
