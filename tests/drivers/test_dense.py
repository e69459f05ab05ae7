"""Dense granular beds (nd.pack_dense): the contact kernels against the NumPy reference, and beds
that are valid, dense, reproducible and say what was wrong with bad input."""

import numpy as np
import pytest

import ndpack as nd
from ndpack.drivers import dense
from ndpack.geometry.period import Period
from ndpack.geometry.soft_contacts import contact_forces, fire_move, largest_move, neighbour_lists, periods


def _random_spheres(dim, count, seed, wrap):
    rng = np.random.default_rng(seed)
    centers = rng.random((count, dim))
    radii = rng.uniform(0.03, 0.08, count)
    period = Period(np.zeros(dim), np.ones(dim), np.ones(dim, bool)) if wrap else None
    centers[:3] = centers[3]  # coincident centres: they part along the first axis
    return centers, radii, period


@pytest.mark.parametrize("dim, wrap", [(2, False), (3, True), (5, True)])
def test_the_compiled_contact_forces_are_numpys(dim, wrap):
    centers, radii, period = _random_spheres(dim, 400, dim, wrap)
    starts, neighbours = neighbour_lists(centers, 2 * radii.max(), period)
    lengths = periods(period, dim)
    compiled = contact_forces(centers, radii, starts, neighbours, lengths, compiled=True)
    reference = contact_forces(centers, radii, starts, neighbours, lengths, compiled=False)
    for mine, theirs in zip(compiled, reference):
        np.testing.assert_allclose(mine, theirs, rtol=1e-12, atol=1e-15)
    forces, energy, overlap = reference
    assert energy.sum() > 0 and overlap.max() > 0
    # Newton's third law: the pushes cancel in all.
    np.testing.assert_allclose(forces.sum(axis=0), 0.0, atol=1e-12)


def test_a_pair_pushes_apart_by_its_overlap_across_a_periodic_face():
    period = Period(np.zeros(2), np.ones(2), np.ones(2, bool))
    centers = np.array([[0.02, 0.5], [0.96, 0.5]])  # 0.06 apart through the face x = 0
    radii = np.array([0.04, 0.04])
    starts, neighbours = neighbour_lists(centers, 0.1, period)
    forces, energy, overlap = contact_forces(centers, radii, starts, neighbours, periods(period, 2))
    np.testing.assert_allclose(forces, [[0.02, 0.0], [-0.02, 0.0]], atol=1e-15)
    np.testing.assert_allclose(energy.sum(), 0.5 * 0.02**2)
    np.testing.assert_allclose(overlap, 0.25)


def test_the_compiled_fire_step_and_moves_are_numpys():
    rng = np.random.default_rng(1)
    centers, velocity, forces = (rng.normal(size=(300, 3)) for _ in range(3))
    moved = [centers.copy(), velocity.copy()], [centers.copy(), velocity.copy()]
    fire_move(*moved[0], forces, 0.1, 0.2, compiled=True)
    fire_move(*moved[1], forces, 0.1, 0.2, compiled=False)
    for mine, theirs in zip(*moved):
        np.testing.assert_allclose(mine, theirs, rtol=1e-13, atol=1e-15)
    lengths = np.array([1.0, np.inf, 2.0])
    assert largest_move(moved[0][0], centers, lengths, True) == pytest.approx(
        largest_move(moved[0][0], centers, lengths, False), rel=1e-13)


def _check_bed(packing, shape):
    assert packing.verify(shape), packing.verify(shape).summary()
    assert packing.params["mode"] == "dense" and packing.params["scale"] > 0
    contacts = packing.params["contacts"]
    assert 0 < contacts["mean"] and contacts["rattlers"] <= len(packing.radii)


def test_equal_spheres_jam_densely_in_a_periodic_cube():
    box = nd.Periodic(nd.Box(np.zeros(3), np.ones(3)))
    packing = nd.pack_dense(box, 1.0, n=400, seed=3, progress=False)
    _check_bed(packing, box)
    assert len(packing.radii) == 400 and np.ptp(packing.radii) == 0
    # Random close packing is about 0.64 (smaller beds a little less); greedy beds stop near 0.42.
    assert packing.fill > 0.6
    # Jammed: the spheres that are not rattlers touch about 2d others (isostatic, 6 in 3-D).
    assert packing.params["contacts"]["backbone_mean"] > 4.0
    assert packing.stop_reason == "jammed"
    assert np.all((packing.centers >= 0) & (packing.centers < 1))  # in the cell


def test_the_same_seed_gives_the_same_bed_and_another_seed_another():
    square = nd.Periodic(nd.Box(np.zeros(2), np.ones(2)))
    radii = np.repeat([0.03, 0.042], 60)  # a bidisperse mix: equal discs would crystallise
    first, again, other = (nd.pack_dense(square, radii, seed=seed, progress=False) for seed in (1, 1, 2))
    np.testing.assert_array_equal(first.centers, again.centers)
    np.testing.assert_array_equal(first.radii, again.radii)
    assert not np.array_equal(first.centers, other.centers)
    assert first.fill > 0.75  # bidisperse discs jam near 0.84


def test_the_numpy_reference_makes_a_valid_bed_too():
    square = nd.Periodic(nd.Box(np.zeros(2), np.ones(2)))
    packing = nd.pack_dense(square, np.repeat([0.05, 0.07], 15), backend="numpy", progress=False)
    _check_bed(packing, square)
    assert packing.fill > 0.7


def test_a_walled_container_holds_every_sphere():
    shape = nd.Ball(np.zeros(3), 1.0) - nd.Ball([0.0, 0.0, 0.9], 0.4)
    packing = nd.pack_dense(shape, 0.12, solid_fraction=0.5, progress=False)
    _check_bed(packing, shape)
    assert packing.fill > 0.45
    assert packing.params["contacts"]["wall"] > 0


def test_a_fraction_the_sizes_reach_keeps_them_and_a_fraction_beyond_jams_smaller():
    box = nd.Periodic(nd.Box(np.zeros(3), np.ones(3)))
    easy = nd.pack_dense(box, 0.08, solid_fraction=0.4, progress=False)
    assert easy.stop_reason == "fraction" and easy.params["scale"] == pytest.approx(1.0, rel=1e-8)
    assert easy.fill == pytest.approx(len(easy.radii) * 4 / 3 * np.pi * 0.08**3, rel=1e-6)
    too_much = nd.pack_dense(box, 0.08, solid_fraction=0.75, progress=False)
    assert too_much.stop_reason == "jammed" and too_much.params["scale"] < 1.0
    _check_bed(too_much, box)


def test_a_size_distribution_keeps_its_shape():
    box = nd.Periodic(nd.Box(np.zeros(3), np.ones(3)))
    distribution = nd.SizeDistribution.discrete([0.05, 0.08], [0.5, 0.5], by="mass")
    packing = nd.pack_dense(box, distribution, solid_fraction=0.5, progress=False)
    _check_bed(packing, box)
    report = distribution.report(packing)
    assert all(abs(c.volume_share - c.target) < 0.05 for c in report.classes)


class _Clock:
    """A clock that moves one second each time it is read: the driver's deadline without wall time."""

    def __init__(self):
        self.now = 0.0

    def perf_counter(self):
        self.now += 1.0
        return self.now


def test_a_time_budget_returns_the_densest_bed_found(monkeypatch):
    box = nd.Periodic(nd.Box(np.zeros(3), np.ones(3)))
    monkeypatch.setattr(dense, "time", _Clock())
    packing = nd.pack_dense(box, 1.0, n=300, time_budget=1.5, progress=False)
    assert packing.stop_reason == "time" and len(packing.params["relaxations"]) == 1
    _check_bed(packing, box)


@pytest.mark.parametrize("call, words", [
    (lambda box: nd.pack_dense(box, 0.05, progress=False), "either n"),
    (lambda box: nd.pack_dense(box, 0.05, n=10, solid_fraction=0.5), "either n"),
    (lambda box: nd.pack_dense(box, 0.05, n=0), "positive whole number"),
    (lambda box: nd.pack_dense(box, 0.05, solid_fraction=1.5), "solid_fraction must lie"),
    (lambda box: nd.pack_dense(box, -1.0, n=10), "sizes must be"),
    (lambda box: nd.pack_dense(box, [0.1, 0.2], n=3), "n=3 but 2 radii"),
    (lambda box: nd.pack_dense(box, 0.05, n=10, backend="warp"), "GPU backends"),
    (lambda box: nd.pack_dense(box, 0.6, solid_fraction=0.3), "scale the sizes"),
    (lambda box: nd.pack_dense(nd.HalfSpace([0, 0, 1], 0.0), 0.1, n=5), "unbounded"),
])
def test_bad_input_says_what_was_wrong(call, words):
    box = nd.Periodic(nd.Box(np.zeros(3), np.ones(3)))
    with pytest.raises(nd.NdpackError, match=words):
        call(box)


def test_the_jamming_guess_covers_every_dimension():
    assert dense.JAMMING[3] == 0.64 and all(0 < dense.JAMMING[d] <= 1 for d in dense.JAMMING)


def test_an_interrupted_bed_keeps_the_densest_state_found(monkeypatch):
    box = nd.Periodic(nd.Box(np.zeros(3), np.ones(3)))
    relax, calls = dense.Bed.relax, []

    def interrupted_third(self, scale):
        calls.append(scale)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return relax(self, scale)

    monkeypatch.setattr(dense.Bed, "relax", interrupted_third)
    packing = nd.pack_dense(box, 1.0, n=200, progress=False)
    assert packing.stop_reason == "interrupted" and len(packing.params["relaxations"]) == 2
    _check_bed(packing, box)


def test_two_spheres_in_a_periodic_cell_stay_narrower_than_its_period():
    square = nd.Periodic(nd.Box(np.zeros(2), np.ones(2)))
    packing = nd.pack_dense(square, 1.0, n=2, progress=False)
    assert packing.radii.max() < 0.5 and packing.verify(square)
