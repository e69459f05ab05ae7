"""Same seed, same packing: bit for bit, on each CPU backend and in both modes; another seed
gives another packing where the random starts matter."""

import hashlib
import os
import subprocess
import sys

import numpy as np
import pytest

import ndpack as nd
from ndpack import backends
from ndpack.errors import BackendError

#: A ball less an octant: no symmetry lines the prototypes up, so the random starts in each
#: cell decide where they converge, and a new seed moves nearly every sphere.
SHAPE = nd.Ball([0, 0, 0], 1) - nd.Box([0, 0, 0], [2, 2, 2])
OPTIONS = dict(n=40, grid=12, progress=False)


def _working(name):
    try:
        backends.get_backend(name)
        return True
    except BackendError:
        return False


BACKENDS = ["numpy", "numba"] + (["warp"] if _working("warp") else [])


def _same(first, second) -> bool:
    return (np.array_equal(first.centers, second.centers) and np.array_equal(first.radii, second.radii)
            and np.array_equal(first.rounds, second.rounds) and np.array_equal(first.stats.count, second.stats.count)
            and np.array_equal(first.medial_axis, second.medial_axis) and first.stop_reason == second.stop_reason)


@pytest.mark.parametrize("mode", ["faithful", "fast"])
@pytest.mark.parametrize("backend", BACKENDS)
def test_same_seed_same_packing_other_seed_other_packing(backend, mode):
    first = nd.pack(SHAPE, seed=3, mode=mode, backend=backend, **OPTIONS)
    again = nd.pack(SHAPE, seed=3, mode=mode, backend=backend, **OPTIONS)
    other = nd.pack(SHAPE, seed=4, mode=mode, backend=backend, **OPTIONS)
    assert len(first) == 40 and _same(first, again)
    # The first sphere is the shape's largest (the same from any start, to the polish); most
    # later ones sit elsewhere.
    moved = np.any(first.centers != other.centers, axis=1)
    assert moved.sum() >= 30 and other.verify().ok
    generator = nd.pack(SHAPE, seed=np.random.default_rng(3), mode=mode, backend=backend, **OPTIONS)
    assert _same(first, generator)  # a Generator seeded alike draws alike


def _digest(packing) -> str:
    return hashlib.sha256(packing.centers.tobytes() + packing.radii.tobytes()).hexdigest()


def test_a_new_process_with_another_hash_seed_packs_the_same():
    # Python salts the hashes of strings per process: an order taken from a set of names would
    # differ between runs that share a seed.
    code = ("import hashlib, ndpack as nd; p = nd.pack(nd.Ball([0, 0, 0], 1) - nd.Box([0, 0, 0], [2, 2, 2]), "
            "n=40, grid=12, seed=3, progress=False, backend='numpy'); "
            "print(hashlib.sha256(p.centers.tobytes() + p.radii.tobytes()).hexdigest())")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300,
                            env={**os.environ, "PYTHONHASHSEED": "12345"})
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == _digest(nd.pack(SHAPE, seed=3, backend="numpy", **OPTIONS))
