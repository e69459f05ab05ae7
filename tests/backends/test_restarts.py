"""Random restarts from a counter-based hash (ndpack.backends.restarts): the host's numbers, the
kernels' numbers, and what a packing needs of them."""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest

import ndpack as nd
from ndpack.backends.numba_common import KERNELS
from ndpack.backends.restarts import Restarts, run_key, stream, units


def _kernel_functions(compiled: bool):
    """The Numba kernels' restart functions, run as Python on NumPy scalars (as the CUDA
    simulator runs them) or compiled by Numba."""
    namespace = {"np": np, "math": math}
    exec(compile(KERNELS, "numba_kernels.py", "exec"), namespace)
    names = ("restart_mix", "restart_key", "restart_unit")
    if compiled:
        for name in names:  # in order: each calls the ones before it
            namespace[name] = numba.njit(namespace[name])
    return [namespace[name] for name in names]


@pytest.mark.parametrize("compiled", [False, True])
def test_numba_kernels_draw_the_hosts_numbers(compiled):
    _, restart_key, restart_unit = _kernel_functions(compiled)
    ids = np.array([0, 1, 7, 4095, 2**31 + 5, 16_000_000])
    dim, tries = 3, 4
    for serial in (1, 2, 977):
        s = stream(run_key(np.random.default_rng(3)), serial)
        expected = units(s, ids, tries, dim)
        got = np.array([[[restart_unit(restart_key(np.uint64(s), int(i)), t * dim + k) for k in range(dim)]
                         for i in ids] for t in range(tries)])
        np.testing.assert_array_equal(got, expected)


def test_units_are_uniform_and_differ_between_restarts_and_prototypes():
    key = run_key(np.random.default_rng(0))
    draws = units(stream(key, 1), np.arange(20_000), 4, 3)
    assert draws.shape == (4, 20_000, 3) and draws.min() >= 0 and draws.max() < 1
    # Each axis and try uniform: mean 1/2, variance 1/12, within 5 standard errors.
    flat = draws.reshape(-1, 3)
    assert np.all(np.abs(flat.mean(axis=0) - 0.5) < 5 * math.sqrt(1 / 12 / len(flat)))
    assert np.all(np.abs(flat.var(axis=0) - 1 / 12) < 0.01)
    # Axes, tries, prototypes and restarts not correlated.
    assert abs(np.corrcoef(flat[:, 0], flat[:, 1])[0, 1]) < 0.02
    assert abs(np.corrcoef(draws[0, :, 0], draws[1, :, 0])[0, 1]) < 0.03
    assert abs(np.corrcoef(draws[0, :-1, 0], draws[0, 1:, 0])[0, 1]) < 0.03
    again = units(stream(key, 2), np.arange(20_000), 4, 3)
    assert abs(np.corrcoef(draws[0, :, 0], again[0, :, 0])[0, 1]) < 0.03
    assert np.array_equal(units(stream(key, 1), np.arange(20_000), 4, 3), draws)  # a hash: repeatable


def test_restart_points_lie_in_the_cells_and_do_not_depend_on_the_chunking():
    rng = np.random.default_rng(1)
    lower = rng.uniform(-1, 0, (50, 2))
    upper = lower + rng.uniform(0.01, 1, (50, 2))
    current = lower + 0.5 * (upper - lower)
    first = rng.uniform(-2, 2, (30, 2))  # for the first 30 prototypes; the others have none
    restarts = Restarts(stream(99, 1), 5, first)
    ids = np.arange(100, 150)
    points = restarts.points(ids, lower, upper, current)
    assert points.shape == (6, 50, 2)
    assert np.all(points >= lower) and np.all(points <= upper)
    np.testing.assert_array_equal(points[0, :30], np.clip(first, lower[:30], upper[:30]))
    np.testing.assert_array_equal(points[0, 30:], current[30:])  # their current point: changes nothing
    for part, rows in ((slice(20, 50), slice(None)), (slice(35, 50), slice(1, None))):  # the last: no first points
        np.testing.assert_array_equal(
            restarts.part(part).points(ids[part], lower[part], upper[part], current[part]), points[rows, part])
    assert Restarts(1, 0).points(ids, lower, upper, current) is None


def test_the_seed_still_chooses_the_packing():
    shape = nd.Box([0.0, 0.0], [1.0, 1.0]) - nd.Ball([0.2, 0.7], 0.3)
    first, again, other = (nd.pack(shape, 30, grid=12, seed=seed, backend="numpy") for seed in (1, 1, 2))
    np.testing.assert_array_equal(first.centers, again.centers)
    assert not np.array_equal(first.centers, other.centers)
