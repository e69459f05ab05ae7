"""The fast mode from 4-D up: its window narrows with the dimension, and ties (a ridge of equal
gaps) are taken one layer at a time, as the faithful mode takes them."""

import numpy as np
import ndpack as nd
from ndpack.drivers.greedy import rounds
from ndpack.drivers.greedy.rounds import FAST_WINDOW, fast_window


def test_the_window_is_the_plain_one_up_to_3d_and_narrows_above():
    assert fast_window(2) == fast_window(3) == FAST_WINDOW
    widths = [fast_window(dim) for dim in range(3, 7)]
    assert all(wider > narrower for wider, narrower in zip(widths, widths[1:]))
    assert 0.02 < fast_window(6) < 0.03
    assert fast_window(12) == fast_window(6)  # no narrower: rounds of a few spheres cost more than they gain


def shell(dim):
    return nd.Ball(np.zeros(dim), 1.0) - nd.Ball(np.zeros(dim), 0.5)


def largest_size(packing):
    """How many spheres of the shell's largest size (radius 1/4) the packing holds."""
    return int(np.count_nonzero(packing.radii >= 0.2499))


def test_a_ridge_of_equal_gaps_is_filled_sphere_beside_sphere(monkeypatch):
    # Every point of the 3-sphere of radius 3/4 is the centre of a largest gap (radius 1/4). The
    # faithful mode places 51 such spheres, each touching those before it; a fast round that kept
    # any disjoint set of its candidates parked 43 at random along the ridge.
    packing = nd.pack(shell(4), n=80, mode="fast", backend="numba", seed=0, progress=False)
    assert packing.verify().ok
    assert largest_size(packing) >= 50
    monkeypatch.setattr(rounds, "TIE_DIMS", (99, 99))  # the plain choice, for comparison
    plain = nd.pack(shell(4), n=80, mode="fast", backend="numba", seed=0, progress=False)
    assert largest_size(plain) < largest_size(packing)


def test_a_tie_round_takes_the_tie_only_and_spaces_its_seeds():
    # The first round of the shell: no spheres yet, so every tied candidate is a seed, kept only
    # two of its radii clear of those kept before it; the smaller candidates wait.
    packing = nd.pack(shell(4), n=80, mode="fast", backend="numba", seed=0, progress=False)
    first = packing.stats.count[0]
    centers = packing.centers[:first]
    assert np.all(packing.radii[:first] >= 0.2499)
    gaps = np.linalg.norm(centers[:, None] - centers[None], axis=2) - 0.5
    np.fill_diagonal(gaps, np.inf)
    assert gaps.min() >= 2 * 0.25 * 0.999


def test_the_fast_mode_fills_as_the_faithful_one_in_a_4d_shell():
    # Means of two seeds (a greedy packing of a few hundred spheres varies by ~0.5% with the seed); 5-D
    # and 6-D, and other shapes, are bench/fast_fill.py's.
    def mean_fill(mode):
        return np.mean([nd.pack(shell(4), n=200, mode=mode, backend="numba", seed=seed, progress=False).fill
                        for seed in (0, 1)])

    assert mean_fill("fast") >= 0.995 * mean_fill("faithful")
