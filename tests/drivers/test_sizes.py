"""Size distributions and the size-distribution driver (pack_sizes)."""

import numpy as np
import pytest

import ndpack as nd
from ndpack.drivers.sizes import SizeDistribution

CYLINDER = nd.Cylinder([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 0.5) & nd.Slab([0.0, 0.0, 1.0], 0.0, 1.0)


# ---------------------------------------------------------------------- distributions
def test_quantile_radii_follow_the_distribution():
    lognormal = SizeDistribution.lognormal(0.02, 0.3, by="count")
    radii = lognormal.radii(3, 4000)
    assert np.all(np.diff(radii) <= 0)  # largest first
    assert abs(np.median(radii) / 0.02 - 1) < 1e-3
    assert abs(np.log(radii).std() / 0.3 - 1) < 0.05  # cut at 3 sigma: a little narrower

    # By mass, a log-normal law's count median is exp(-3 sigma^2) lower in 3-D (Hatch-Choate).
    by_mass = SizeDistribution.lognormal(0.02, 0.3, by="mass", low=0.02 * np.exp(-5 * 0.3),
                                         high=0.02 * np.exp(5 * 0.3))
    assert abs(np.median(by_mass.radii(3, 4000)) / (0.02 * np.exp(-3 * 0.3**2)) - 1) < 0.01


def test_discrete_classes_by_mass_become_counts():
    bimodal = SizeDistribution.discrete([0.04, 0.01], [0.5, 0.5], by="mass")
    radii = bimodal.radii(3, 1300)
    big, small = (radii == 0.04).sum(), (radii == 0.01).sum()
    assert big + small == 1300
    assert abs(small / big - 4**3) < 2  # equal mass: 64 small spheres per large one
    cumulative = SizeDistribution.cumulative([0.01, 0.02, 0.04], [0.0, 0.25, 1.0])
    radii = cumulative.radii(2, 1000)
    assert abs((radii <= 0.02).mean() - 0.25) < 2e-3


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: SizeDistribution.discrete([0.1, -0.1], [1, 1]), "radii must be positive"),
        (lambda: SizeDistribution.discrete([0.1, 0.2], [1]), "fractions must be 2 non-negative"),
        (lambda: SizeDistribution.discrete([0.1, 0.1], [0.5, 0.5]), "must differ"),
        (lambda: SizeDistribution.discrete([0.1, 0.2], [0.6, 0.6]), r"sum to 1 .* sum to 1.2: for relative weights"),
        (lambda: SizeDistribution.cumulative([0.1, 0.2], [0.0, 0.9]), "cdf must rise from 0 to 1"),
        (lambda: SizeDistribution.lognormal(0.1, 0.0), "sigma > 0"),
        (lambda: SizeDistribution.discrete([0.1], [1], by="volume"), "by must be 'count' or 'mass'"),
    ],
)
def test_bad_distributions_are_refused(make, message):
    with pytest.raises(nd.ParameterError, match=message):
        make()


def test_the_report_sees_a_wrong_packing():
    bimodal = SizeDistribution.discrete([0.05, 0.02], [0.5, 0.5], by="count")
    packing = nd.pack(nd.Box([0, 0, 0], [1, 1, 1]), n=200, mode="fast", backend="numba", max_radius=0.05)
    report = bimodal.report(packing)
    assert report.ks > 0.3  # the greedy packing's radii are anything but this
    assert sum(c.count for c in report.classes) == 200


# ---------------------------------------------------------------------- the driver
def check(packing, distribution, ks=0.05, share=0.05):
    report = distribution.report(packing)
    assert packing.verify().ok and packing.repair is None
    assert packing.stop_reason == "count" and packing.params["unplaced"] == 0, packing.params
    assert report.ks <= ks, report
    for size in report.classes:
        got = size.count_share if report.by == "count" else size.volume_share
        assert abs(got - size.target) <= share * size.target, report
    return report


def test_a_lognormal_by_mass_in_a_cylinder():
    lognormal = SizeDistribution.lognormal(0.02, 0.25, by="mass")
    packing = nd.pack_sizes(CYLINDER, lognormal, n=10_000, backend="numba")
    assert len(packing) == 10_000
    report = check(packing, lognormal)
    assert packing.radii.max() <= lognormal.largest and packing.radii.min() >= lognormal.smallest
    assert report.solid_fraction > 0.3


def test_a_bimodal_solid_fraction_in_a_cylinder():
    bimodal = SizeDistribution.discrete([0.04, 0.015], [0.6, 0.4], by="mass")
    packing = nd.pack_sizes(CYLINDER, bimodal, solid_fraction=0.45, backend="numba")
    report = check(packing, bimodal)
    assert abs(report.solid_fraction - 0.45) < 0.01  # the shape's volume is a Monte Carlo estimate


def test_a_polygon_and_a_4d_box():
    outline = nd.Polygon([[0, 0], [1, 0], [1, 0.6], [0.5, 1.0], [0, 0.6]])
    classes = SizeDistribution.discrete([0.03, 0.015, 0.008], [0.3, 0.3, 0.4], by="count")
    check(nd.pack_sizes(outline, classes, n=400, backend="numba"), classes)
    sand = SizeDistribution.lognormal(0.004, 0.25, by="mass")
    assert check(nd.pack_sizes(outline, sand, n=10_000, backend="numba"), sand).solid_fraction > 0.5
    lognormal = SizeDistribution.lognormal(0.08, 0.2, by="count")
    box = nd.Box(np.zeros(4), np.ones(4))
    check(nd.pack_sizes(box, lognormal, n=600, backend="numba", grid=8), lognormal)


def test_radii_that_do_not_fit_are_given_up_and_counted():
    huge = SizeDistribution.discrete([0.3, 0.05], [0.5, 0.5], by="count")
    packing = nd.pack_sizes(nd.Box([0, 0], [1, 1]), huge, n=40, backend="numba")
    # A unit square holds 4 circles of 0.3 at most (two of 0.3 side by side need 1.2).
    assert packing.stop_reason == "no_room" and packing.params["unplaced"] > 0
    assert (packing.radii == 0.3).sum() + packing.params["unplaced"] >= 20
    assert packing.verify().ok


def test_same_packing_on_the_reference_backend():
    classes = SizeDistribution.discrete([0.05, 0.02], [0.5, 0.5], by="count")
    square = nd.Box([0, 0], [1, 1])
    packings = [nd.pack_sizes(square, classes, n=50, grid=32, backend=name) for name in ("numpy", "numba")]
    assert all(p.verify().ok and p.stop_reason == "count" for p in packings)
    np.testing.assert_array_equal(np.sort(packings[0].radii), np.sort(packings[1].radii))


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(), "either n .* or solid_fraction"),
        (dict(n=10, solid_fraction=0.3), "either n"),
        (dict(solid_fraction=1.2), r"solid_fraction must lie in \(0, 1\)"),
        (dict(n=0), "n .*positive integer"),
    ],
)
def test_bad_driver_input_is_refused(kwargs, message):
    classes = SizeDistribution.discrete([0.05], [1.0])
    with pytest.raises(nd.ParameterError, match=message):
        nd.pack_sizes(nd.Box([0, 0], [1, 1]), classes, **kwargs)
    with pytest.raises(nd.ParameterError, match="must be an ndpack.SizeDistribution"):
        nd.pack_sizes(nd.Box([0, 0], [1, 1]), [0.1, 0.2], n=5)
    with pytest.raises(nd.ParameterError, match="more than half the shape's largest extent"):
        nd.pack_sizes(nd.Box([0, 0], [1, 1]), SizeDistribution.discrete([0.9], [1.0]), n=5)
