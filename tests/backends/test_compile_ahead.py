"""Compile helpers (ndpack.compile_ahead): the jobs shared so that helpers finish together, and what
a helper compiles is what this process then loads, not compiles again (issue 48: a fresh GPU
machine's first packing of a mesh compiled for 40.9 s with numba-cuda, one kernel after another)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import pytest

from ndpack import compile_ahead


def test_jobs_are_shared_heaviest_first_so_that_helpers_finish_together():
    jobs = [(name, weight, "ndpack.x:f", []) for name, weight in
            (("a", 1.0), ("b", 5.0), ("c", 3.9), ("d", 0.1), ("e", 0.1), ("f", 3.0), ("g", 1.9))]
    groups = compile_ahead.share(jobs, 3)
    names = [[job[0] for job in group] for group in groups]
    assert names == [["b"], ["c", "a", "d"], ["f", "g", "e"]]
    loads = [sum(job[1] for job in group) for group in groups]
    assert max(loads) - min(loads) <= 1.0
    assert [len(group) for group in compile_ahead.share(jobs[:2], 8)] == [1, 1]  # no empty helpers
    assert sum(len(group) for group in compile_ahead.share(jobs, 1)) == len(jobs)


def test_helpers_follow_the_setting_and_the_cores(monkeypatch):
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: set(range(16)), raising=False)
    monkeypatch.delenv("NDPACK_COMPILE_AHEAD", raising=False)
    monkeypatch.delenv("NUMBA_NUM_THREADS", raising=False)
    assert compile_ahead.helpers_allowed(3) == compile_ahead.HELPERS_MOST
    monkeypatch.setenv("NUMBA_NUM_THREADS", "4")  # a local pool's worker: its share of the cores
    assert compile_ahead.helpers_allowed(3) == 3
    monkeypatch.setenv("NUMBA_NUM_THREADS", "1")
    assert compile_ahead.helpers_allowed(1) == 0
    monkeypatch.delenv("NUMBA_NUM_THREADS")
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1}, raising=False)
    assert compile_ahead.helpers_allowed(1) == 1 and compile_ahead.helpers_allowed(3) == 0  # 2 cores: one
    monkeypatch.setenv("NDPACK_COMPILE_AHEAD", "1")
    assert compile_ahead.helpers_allowed(3) == 3
    monkeypatch.setenv("NDPACK_COMPILE_AHEAD", "0")
    assert compile_ahead.helpers_allowed(1) == 0
    assert not compile_ahead.start([("k", 1.0, "ndpack.compile_ahead:under_way", [])])


def test_jobs_whose_helper_could_not_start_are_not_waited_for(monkeypatch):
    """Where the system refuses a second helper, the first runs its jobs and the others are not under
    way (this process compiles them itself): nothing waits for a helper that does not exist."""
    monkeypatch.setenv("NDPACK_COMPILE_AHEAD", "1")
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: set(range(4)), raising=False)
    started = []
    real_popen = subprocess.Popen

    def popen(*args, **kwargs):
        if started:
            raise OSError("no more processes")
        started.append(real_popen(*args, **kwargs))
        return started[-1]

    monkeypatch.setattr(subprocess, "Popen", popen)
    jobs = [(f"job {k}", 1.0, "ndpack.compile_ahead:under_way", []) for k in range(3)]
    try:
        assert compile_ahead.start(jobs)
        assert compile_ahead.under_way() == ["job 0"]  # three helpers asked, one started
        compile_ahead.wait("job 0")
        assert started[0].returncode == 0 and compile_ahead.under_way() == []  # its helper ran its job and ended
        compile_ahead.wait("job 1")  # never under way: nothing to wait for, and nothing started
        assert len(started) == 1 and compile_ahead.under_way() == []
    finally:
        compile_ahead._stop_helpers()


def test_a_helper_runs_only_ndpacks_functions():
    done = subprocess.run([sys.executable, "-c", compile_ahead.HELPER, json.dumps([["os:system", ["true"]]])],
                          capture_output=True, text=True)
    assert done.returncode != 0 and "ndpack's functions only" in done.stderr


def _fresh_caches(tmp_path) -> dict:
    return dict(os.environ, NDPACK_CACHE=str(tmp_path / "ndpack"), NUMBA_CACHE_DIR=str(tmp_path / "numba"),
                NDPACK_COMPILE_AHEAD="1", PYTHONPATH=os.pathsep.join(sys.path))


# Under the CUDA simulator (no GPU here), a packing's launches with their arguments' Numba types,
# against the signatures the helpers compile for (ENTRY_TYPES): a launch with other types would
# compile again, in the main process, after waiting for its helper.
SIGNATURES = textwrap.dedent("""
    import json
    import numba
    import numpy as np
    import trimesh
    import ndpack as nd
    from ndpack.kernels import compile as kernel_compile
    from ndpack.backends import numba_cuda_backend as ncb

    seen = {}
    first_launch = kernel_compile.CudaKernel.__getitem__

    def recording(self, config):
        launch = first_launch(self, config)
        name = getattr(self.kernel, "py_func", None) or self.kernel.fn
        def run(*args):
            types = tuple(str(numba.typeof(getattr(a, "_ary", a))) for a in args)
            seen.setdefault(name.__name__, set()).add(types)
            return launch(*args)
        return run

    kernel_compile.CudaKernel.__getitem__ = recording
    backend = nd.backends.get_backend("numba-cuda")
    backend.launch_bound = True  # a GPU's policies: the polish ahead selects with select_all
    sphere = trimesh.creation.icosphere(subdivisions=1)
    for shape, n in ((nd.TriangleMesh(sphere.vertices, sphere.faces), 12), (nd.Box([0, 0, 0], [1, 1, 1]), 40)):
        nd.pack(shape, n, backend=backend, mode="fast", seed=0, grid=4, progress=False, on_invalid="raise")
    # The host store's queries (a 4-D round's ties call near_spheres).
    rng = np.random.default_rng(0)
    centers, radii, points = rng.random((20, 3)), np.full(20, 0.05), rng.random((5, 3))
    backend.near_spheres(points, points + 0.1, np.full(5, 0.2), centers, radii)
    backend.touched(points, np.full(5, 0.1), centers, radii)
    wrong = {}
    for name, signatures in seen.items():
        expected = tuple(str(ncb.numba_type(kind)) for kind in ncb.ENTRY_TYPES[name])
        if signatures != {expected}:
            wrong[name] = [sorted(signatures), expected]
    print(json.dumps({"launched": sorted(seen), "wrong": wrong}))
""")


def test_the_signatures_compiled_ahead_are_those_a_packing_launches(tmp_path):
    pytest.importorskip("numba_cuda")
    env = dict(_fresh_caches(tmp_path), NUMBA_ENABLE_CUDASIM="1")
    done = subprocess.run([sys.executable, "-c", SIGNATURES], env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-3000:]
    report = json.loads(done.stdout.strip().splitlines()[-1])
    assert report["wrong"] == {}
    from ndpack.backends.numba_cuda_backend import ENTRY_TYPES

    assert set(report["launched"]) == set(ENTRY_TYPES)  # every entry point checked


GRIDS = textwrap.dedent("""
    import json
    import numpy as np
    from ndpack import compile_ahead
    from ndpack.geometry import close_pairs, overlaps

    compile_ahead.start(close_pairs.ahead_jobs() + overlaps.ahead_jobs())  # as a packing starts them
    under_way = compile_ahead.under_way()
    rng = np.random.default_rng(1)
    centers, radii = rng.random((500, 3)), np.full(500, 0.02)
    found = close_pairs.grid(centers, radii, 1e-9, 0.02)
    pairs = found.pairs()
    near = found.count_near(np.arange(10), 0.05, 100)
    with_ids = found.pairs_with(np.arange(5))
    overlapping = overlaps.overlapping_pairs(centers, radii, 0.0)
    stats = {}
    for module in (close_pairs, overlaps):
        for dispatcher in module._kernels():
            stats[dispatcher.py_func.__name__ + " " + module.__name__] = [
                sum(dispatcher.stats.cache_hits.values()), sum(dispatcher.stats.cache_misses.values())]
    assert close_pairs.ahead_jobs() == overlaps.ahead_jobs() == []  # on disk now: no job
    print(json.dumps({"under_way": under_way, "again": compile_ahead.under_way(), "stats": stats,
                      "pairs": len(pairs[0]), "overlaps": len(overlapping[0])}))
""")


def test_the_checks_grids_compiled_by_helpers_are_loaded_not_compiled_again(tmp_path):
    done = subprocess.run([sys.executable, "-c", GRIDS], env=_fresh_caches(tmp_path), capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-3000:]
    report = json.loads(done.stdout.strip().splitlines()[-1])
    assert report["under_way"] == sorted(["numba: the conflict check's grid", "numba: the overlap check's grid"])
    assert report["again"] == []
    assert report["pairs"] > 0 and report["overlaps"] > 0  # the kernels ran, loaded from disk
    # Every kernel this process called came from the helpers' disk cache; none compiled here.
    called = {name: counts for name, counts in report["stats"].items() if sum(counts)}
    assert called and all(hits > 0 and misses == 0 for hits, misses in called.values()), report["stats"]


MESH = textwrap.dedent("""
    import json
    import numpy as np
    import trimesh
    import ndpack as nd
    from ndpack import compile_ahead
    from ndpack.meshes import bvh, layout, queries

    sphere = trimesh.creation.icosphere(subdivisions=2)
    started = []
    real_start = compile_ahead.start
    compile_ahead.start = lambda jobs, least=1: started.extend(job[0] for job in jobs) or real_start(jobs, least)
    mesh = nd.TriangleMesh(sphere.vertices, sphere.faces)  # loading compiles the tree, winding data, sign check
    mesh.closest_points([[0.1, 0.2, 0.3]])
    mesh._step_inside(np.array([[2.0, 0.1, 0.2]]), np.array([[0.5, -1.0, -1.0]]), np.array([[2.0, 1.0, 1.0]]), 3, 1e-8)
    dispatchers = [bvh._compiled(), layout._compiled_winding_data(), *(queries._namespace()[name]
                                                                       for name in queries.SIGNATURES)]
    stats = {d.py_func.__name__: [sum(d.stats.cache_hits.values()), sum(d.stats.cache_misses.values())]
             for d in dispatchers}
    print(json.dumps({"started": sorted(started), "stats": stats}))
""")


def test_a_meshs_kernels_compiled_by_helpers_are_loaded_not_compiled_again(tmp_path):
    """Loading a mesh on a fresh machine: its tree's build, winding data and queries compiled by
    helpers for the signatures written beside them, which are those loading it calls them with."""
    done = subprocess.run([sys.executable, "-c", MESH], env=_fresh_caches(tmp_path), capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-3000:]
    report = json.loads(done.stdout.strip().splitlines()[-1])
    from ndpack.meshes import queries

    assert len(report["started"]) == 2 + len(queries.SIGNATURES), report  # the tree, the winding data, the queries
    assert all(hits > 0 and misses == 0 for hits, misses in report["stats"].values()), report["stats"]
