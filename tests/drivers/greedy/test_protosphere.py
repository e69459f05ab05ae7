"""The ProtoSphere driver: exact cases, validity in 2D-6D, options, stopping, bad input."""

import numpy as np
import pytest

import ndpack as nd
from ndpack.drivers.greedy import protosphere
from ndpack.backends.numpy_backend import NumpyBackend
from ndpack.drivers.greedy.protosphere import cooling_schedule, grid_counts, schedules


def corner_radius(dim):
    return 0.5 * (np.sqrt(dim) - 1) / (np.sqrt(dim) + 1)


@pytest.mark.parametrize("dim", [2, 3, 4])
def test_unit_cube_centre_then_corners(dim):
    packing = nd.pack(nd.Box(np.zeros(dim), np.ones(dim)), n=1 + 2**dim, seed=0)
    assert len(packing) == 1 + 2**dim
    assert abs(packing.radii[0] - 0.5) / 0.5 < 1e-4
    np.testing.assert_allclose(packing.centers[0], 0.5, atol=1e-4)
    assert np.abs(packing.radii[1:] / corner_radius(dim) - 1).max() < 1e-4
    # One sphere per corner: the nearest corner of each is at distance r * sqrt(d).
    corners = np.round(packing.centers[1:])
    assert len(np.unique(corners, axis=0)) == 2**dim
    np.testing.assert_allclose(
        np.linalg.norm(packing.centers[1:] - corners, axis=1), packing.radii[1:] * np.sqrt(dim), rtol=1e-4
    )
    assert packing.verify().ok


@pytest.mark.parametrize("dim", [2, 3, 5])
def test_first_sphere_in_a_ball_is_the_ball(dim):
    center = np.linspace(-1, 1, dim)
    packing = nd.pack(nd.Ball(center, 2.0), n=1, seed=1)
    assert abs(packing.radii[0] - 2.0) / 2.0 < 1e-4
    np.testing.assert_allclose(packing.centers[0], center, atol=1e-3)


def shapes_in(dim):
    """Every analytic N-D shape kind, bounded, plus CSG with thin parts and holes."""
    zero, one = np.zeros(dim), np.ones(dim)
    box = nd.Box(-one, one)
    shapes = {
        "ball": nd.Ball(zero, 1.0),
        "box": box,
        "rounded box": nd.RoundedBox(-one, one, 0.3),
        "half-space & box": nd.HalfSpace(np.arange(1.0, dim + 1), 0.2) & box,
        "slab & ball": nd.Slab(one, -0.3, 0.5) & nd.Ball(zero, 1.0),
        "capsule": nd.Capsule(-0.5 * one, 0.5 * one, 0.3),
        "cylinder": nd.Cylinder(zero, np.eye(dim)[0], 0.4),
        "polytope": nd.ConvexPolytope(np.vstack([np.eye(dim), -np.ones((1, dim))]), np.r_[one, 0.5]),
        "simplex": nd.Simplex(np.vstack([zero, np.eye(dim)])),
        "ellipsoid": nd.Ellipsoid(zero, np.linspace(0.4, 1.0, dim)),
        "box with a hole": box - nd.Ball(zero, 0.6),
        "thin shell": nd.Ball(zero, 1.0).shell(0.12),
        "rotated union": (nd.Box(-one, 0.2 * one) | nd.Ball(0.5 * one, 0.5)).rotate(nd.rotation(dim, 0.3)),
        "smooth union": nd.Ball(-0.3 * np.eye(dim)[0], 0.5).smooth_union(nd.Ball(0.3 * np.eye(dim)[1], 0.4), 0.3),
        "eroded, scaled, moved": box.offset(-0.2).scale_by(0.5).translate(one),
    }
    if dim == 2:
        shapes["polygon with hole"] = nd.Polygon(
            [[0, 0], [3, 0], [3, 1], [1, 1], [1, 3], [0, 3]], holes=[[[0.3, 0.3], [0.6, 0.3], [0.6, 0.6]]]
        )
    if dim == 3:
        shapes["torus"] = nd.Torus(zero, 1.0, 0.25)
    return shapes


CASES = [(dim, name) for dim in range(2, 7) for name in shapes_in(dim)]


@pytest.mark.parametrize("dim, name", CASES, ids=[f"{d}d-{n}" for d, n in CASES])
def test_packings_of_every_shape_are_valid(dim, name):
    shape = shapes_in(dim)[name]
    packing = nd.pack(shape, n=25, grid=6 if dim > 3 else 16, seed=2)
    report = nd.verify(packing, shape)
    assert report.ok, report.summary()
    # The first sphere in a ball is the ball: nothing else fits.
    assert len(packing) == (1 if name == "ball" else 25)
    # Strictly inside, by the safety margin.
    assert report.worst_containment < 0


@pytest.mark.parametrize(
    "shape",
    [nd.Box([0, 0], [1, 1]), nd.Box([0, 0, 0], [1, 1, 1]), nd.Box([0, 0], [1, 1]) - nd.Ball([0.3, 0.4], 0.2)],
    ids=["square", "cube", "square with a hole"],
)
def test_greedy_order_is_largest_first_on_the_default_grid(shape):
    # On coarse grids one cell can hide a second, larger local maximum; on the default grid
    # these shapes come out in exact largest-first order (the faithful mode's; the fast mode
    # takes a window of near-equal radii a round).
    radii = nd.pack(shape, n=150, seed=0, mode="faithful").radii
    assert np.all(np.diff(radii) <= 1e-9 * radii[:-1])


def test_fill_statistics_grow_and_match_the_spheres():
    packing = nd.pack(nd.Box([0, 0], [1, 1]), n=200, seed=0)
    fill = packing.stats.fill
    assert np.all(np.diff(fill) > 0)
    assert np.all(np.diff(packing.stats.time) >= 0)
    assert packing.stats.count[-1] == len(packing) == 200
    assert fill[-1] == pytest.approx(packing.fill, rel=1e-12)
    assert packing.fill == pytest.approx(np.pi * np.sum(packing.radii**2), rel=1e-12)
    # An Apollonian packing of the square covers most of it with 200 circles.
    assert 0.9 < packing.fill < 1


def test_batch_packs_disjoint_spheres_with_similar_fill():
    square = nd.Box([0, 0], [1, 1])
    exact = nd.pack(square, n=300, seed=0, mode="faithful")
    batched = nd.pack(square, n=300, batch=16, seed=0)
    assert batched.verify().ok
    assert len(batched) == 300
    assert batched.stats.count.size < exact.stats.count.size / 4
    assert abs(batched.fill - exact.fill) / exact.fill < 0.01


def test_same_seed_same_packing_and_other_seed_still_valid():
    shape = nd.Ball([0, 0, 0], 1) - nd.Box([0, 0, 0], [2, 2, 2])
    first = nd.pack(shape, n=40, seed=5)
    second = nd.pack(shape, n=40, seed=5)
    np.testing.assert_array_equal(first.centers, second.centers)
    np.testing.assert_array_equal(first.radii, second.radii)
    assert nd.pack(shape, n=40, seed=6).verify().ok


def test_stop_conditions():
    square = nd.Box([0, 0], [1, 1])
    by_radius = nd.pack(square, n=10_000, min_radius=0.05, seed=0)
    assert by_radius.stop_reason == "min_radius"
    assert by_radius.radii.min() >= 0.05
    by_fill = nd.pack(square, n=10_000, fill=0.8, seed=0)
    assert by_fill.stop_reason == "fill"
    assert by_fill.fill >= 0.8 and by_fill.stats.fill[-2] < 0.8
    by_time = nd.pack(square, n=10**6, time_budget=2.0, seed=0)  # 0.5 s placed none on a busy machine
    assert by_time.stop_reason == "time"
    assert 0 < len(by_time) < 10**6 and by_time.verify().ok


@pytest.mark.parametrize("mode", ["fast", "faithful"])
def test_a_time_budget_holds_inside_long_rounds(mode, monkeypatch):
    """Each prototype move made to last 2 ms: a fast round's refinement (hundreds of them) or a
    faithful round's revivals would overrun a 1.5 s budget by seconds if time were checked only
    between rounds; the packing stops within a few pieces of the budget, and is what it made."""
    import time

    from ndpack.backends.prototypes import HostPrototypes

    move = HostPrototypes.move

    def slow(self, ids, *args, **kwargs):
        time.sleep(2e-3 * len(ids))
        return move(self, ids, *args, **kwargs)

    monkeypatch.setattr(HostPrototypes, "move", slow)
    started = time.perf_counter()
    packing = nd.pack(nd.Box([0, 0, 0], [1, 1, 1]), n=10**6, grid=12, mode=mode, time_budget=1.5, backend="numba")
    packed = time.perf_counter() - started - (packing.stats.time[-1] if len(packing.stats.time) else 0)
    assert packing.stop_reason == "time" and len(packing) > 0
    assert packing.stats.time[-1] < 1.5 * 1.3, packing.stats.time[-1]  # the last round ended near the budget
    assert packed < 5.0  # what follows the last round: the float64 check, not more packing


def test_medial_axis_of_a_rectangle():
    rectangle = nd.Box([0, 0], [2, 1])
    packing = nd.pack(rectangle, n=1, grid=40, seed=0)
    axis, radii = packing.medial_axis, packing.medial_radii
    assert axis.shape[1] == 2 and radii.shape == (len(axis),)
    np.testing.assert_allclose(radii, -rectangle.distance(axis), rtol=1e-12)
    # Cells crossed by the middle segment y = 0.5, 0.5 < x < 1.5 hold converged points on it.
    middle = axis[(axis[:, 0] > 0.6) & (axis[:, 0] < 1.4)]
    on_axis = np.abs(middle[:, 1] - 0.5) < 1e-4
    assert on_axis.sum() >= 0.8 * 40 * 0.8 / 2


def test_interrupt_keeps_what_was_packed():
    def interrupted_in_the_fifth_round(round):
        if round.index == 4:
            raise KeyboardInterrupt  # what Ctrl-C raises

    packing = nd.pack(nd.Box([0, 0], [1, 1]), n=1000, seed=0, mode="faithful", on_round=interrupted_in_the_fifth_round)
    assert packing.stop_reason == "interrupted"
    assert len(packing) == 5 and packing.verify().ok
    assert len(packing.stats.count) == 5


def test_on_round_sees_every_round_and_can_stop_the_run():
    rounds = []

    def watch(round):
        rounds.append(round)
        return round.count >= 40

    packing = nd.pack(nd.Box([0, 0], [1, 1]), n=1000, mode="fast", backend="numba", on_round=watch)
    assert packing.stop_reason == "callback"
    assert [r.index for r in rounds] == list(range(len(rounds)))
    assert rounds[-1].count == len(packing) >= 40 > rounds[-2].count
    # The rounds' spheres are the packing's, in order, and the fill and counts are its stats.
    np.testing.assert_array_equal(np.concatenate([r.radii for r in rounds]), packing.radii)
    np.testing.assert_array_equal([r.count for r in rounds], packing.stats.count)
    np.testing.assert_allclose([r.fill for r in rounds], packing.stats.fill)
    with pytest.raises(nd.ParameterError, match="on_round must be a function"):
        nd.pack(nd.Box([0, 0], [1, 1]), n=3, on_round=3)


def test_invalid_spheres_are_repaired_before_they_are_returned():
    # The last line of defence against oracles that are not conservative: spheres that fail
    # verification are shrunk (or dropped), the user is warned, and the packing records it.
    from ndpack.drivers.greedy.protosphere import _ensure_valid

    square = nd.Box([0, 0], [1, 1])
    raw = nd.Packing(
        centers=np.array([[0.5, 0.5], [0.9, 0.5], [0.05, 0.05]]),
        radii=np.array([0.3, 0.2, 0.1]),  # the second overlaps the first; it and the third poke out
        rounds=np.arange(3),
        volume=1.0,
    )
    with pytest.warns(nd.RepairWarning, match="not conservative"):
        fixed = _ensure_valid(raw, square, margin=1e-10, on_invalid="repair")
    assert nd.verify(fixed, square).ok
    assert len(fixed) == 3
    assert fixed.radii[0] == 0.3 and fixed.radii[1] < 0.1
    assert fixed.repair["outside"] == 2 and fixed.repair["overlapping_pairs"] == 1
    assert fixed.repair["shrunk"] == 2 and fixed.repair["dropped"] == 0
    assert fixed.repair["worst_overlap"] == pytest.approx(0.1)
    assert "REPAIRED" in fixed.summary() and raw.repair is None
    with pytest.raises(nd.InvalidPackingError, match="2 sphere\\(s\\) poked out and 1 pair"):
        _ensure_valid(raw, square, margin=1e-10, on_invalid="raise")


class _OverstatingBackend(NumpyBackend):
    """The reference with every clearance 2% too large: a backend that makes overlaps every round."""

    name = "overstating"

    def converge(self, *args, **kwargs):
        points, clearance = super().converge(*args, **kwargs)
        return points, clearance * 1.02


def test_a_backend_that_overstates_fails_instead_of_being_repaired_unseen():
    # What the suite's validity assertions rest on: the driver no longer repairs silently. In
    # the tests (NDPACK_ON_INVALID=raise) a packing with overlaps raises; the old driver shrank
    # the spheres and returned a packing that passed verify().ok.
    square = nd.Box([0, 0], [1, 1])
    with pytest.raises(nd.InvalidPackingError, match="overlapped|poked out"):
        nd.pack(square, n=40, grid=16, backend=_OverstatingBackend())
    # Asked for, the repair still happens, and says so in the packing and its files.
    with pytest.warns(nd.RepairWarning):
        repaired = nd.pack(square, n=40, grid=16, backend=_OverstatingBackend(), on_invalid="repair")
    assert repaired.verify().ok and repaired.repair["shrunk"] + repaired.repair["dropped"] > 0


def test_on_invalid_is_checked():
    with pytest.raises(nd.ParameterError, match="on_invalid must be 'repair' or 'raise'"):
        nd.pack(nd.Box([0, 0], [1, 1]), n=2, on_invalid="ignore")


def test_dead_prototypes_are_revived_before_giving_up_for_room():
    # On a coarse grid every prototype's random restarts soon land inside spheres; the revival
    # keeps the run going while free space is left, instead of stopping early for "no room".
    packing = nd.pack(nd.Box([0, 0], [1, 1]), n=600, grid=12, restarts=1, seed=0)
    assert len(packing) == 600 and packing.stop_reason == "count"
    assert packing.verify().ok


def test_cooling_schedule_and_grid():
    steps = cooling_schedule(50)
    assert steps[0] == 0.5 and steps[-1] == pytest.approx(2e-6)
    assert np.all(np.diff(steps) < 0)
    np.testing.assert_array_equal(grid_counts(np.array([[0, 0], [2, 1]]), 10), [10, 5])
    assert abs(np.prod(grid_counts(np.array([[0, 0, 0], [1, 1, 1]]))) - 32768) < 100


@pytest.mark.parametrize("iterations", [1, 5, 50, 200])
def test_fast_mode_cuts_the_schedules_where_they_cool_below_its_floors(iterations):
    steps, polish = schedules("faithful", iterations)
    np.testing.assert_array_equal(steps, cooling_schedule(iterations))
    assert len(polish) == protosphere.POLISH_ITERATIONS and polish[-1] == pytest.approx(protosphere.POLISH_EPS_END)
    fast_steps, fast_polish = schedules("fast", iterations)
    # A prefix: the first steps' travel is kept, only the precision of the tail goes.
    np.testing.assert_array_equal(fast_steps, steps[: len(fast_steps)])
    np.testing.assert_array_equal(fast_polish, polish[: len(fast_polish)])
    assert fast_steps.min() >= protosphere.FAST_EPS_END and fast_polish.min() >= protosphere.FAST_POLISH_EPS_END
    if len(fast_steps) < len(steps):
        assert steps[len(fast_steps)] < protosphere.FAST_EPS_END
    assert polish[len(fast_polish)] < protosphere.FAST_POLISH_EPS_END


def test_a_fast_packing_records_where_its_schedules_stop():
    packing = nd.pack(nd.Box([0, 0], [1, 1]), n=20, mode="fast", seed=0)
    assert packing.params["fast_eps_end"] == protosphere.FAST_EPS_END
    assert packing.params["fast_polish_eps_end"] == protosphere.FAST_POLISH_EPS_END
    assert "fast_eps_end" not in nd.pack(nd.Box([0, 0], [1, 1]), n=5, seed=0).params


@pytest.mark.parametrize("dim, n, batch, chosen", [
    (2, 101, 1, "fast"), (3, 101, 1, "fast"), (3, 100, 1, "faithful"), (4, 5000, 1, "fast"),
    (6, 101, 1, "fast"), (5, 100, 1, "faithful"), (3, 5000, 4, "faithful"),
])
def test_auto_mode_is_fast_for_many_spheres_in_every_dimension_and_says_why(dim, n, batch, chosen):
    mode, why = protosphere.choose_mode("auto", n, dim, batch)
    assert mode == chosen and why.startswith("auto: ")
    assert protosphere.choose_mode("faithful", n, dim, batch) == ("faithful", None)


def test_the_default_mode_is_auto_and_records_what_it_ran():
    few = nd.pack(nd.Box([0, 0], [1, 1]), n=10, seed=0, backend="numpy")
    many = nd.pack(nd.Box([0, 0], [1, 1]), n=150, seed=0, backend="numpy")
    assert few.params["mode"] == "faithful" and "n=10" in few.params["mode_why"]
    assert many.params["mode"] == "fast" and "fast_eps_end" in many.params
    asked = nd.pack(nd.Box([0, 0], [1, 1]), n=150, seed=0, backend="numpy", mode="faithful")
    assert asked.params["mode"] == "faithful" and "mode_why" not in asked.params


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(n=0), "n .*positive integer"),
        (dict(n=2.5), "n .*positive integer"),
        (dict(n="many"), "n .*positive integer"),
        (dict(iterations=0), "iterations must be a positive integer"),
        (dict(batch=-1), "batch must be a positive integer"),
        (dict(fill=1.5), r"fill .* must lie in \(0, 1\)"),
        (dict(min_radius=-1), "min_radius must be a non-negative"),
        (dict(time_budget=0), "time_budget must be a positive"),
        (dict(grid=0), "grid must be a positive integer"),
        (dict(grid=[4, 4, 4]), "grid must be a positive integer or 2"),
        (dict(grid=10_000), "too large"),
    ],
)
def test_impossible_parameters_are_refused(kwargs, message):
    with pytest.raises(nd.ParameterError, match=message):
        nd.pack(nd.Box([0, 0], [1, 1]), **kwargs)


def test_bad_shapes_are_refused_with_clear_errors():
    with pytest.raises(nd.ShapeError, match="no interior point.* steps across its boundary"):
        nd.pack(nd.Box([0, 0], [1, 1]) - nd.Ball([0.5, 0.5], 2.0), n=5)
    with pytest.raises(nd.BoundsError, match="unbounded"):
        nd.pack(nd.HalfSpace([1, 0], 0.0), n=5)
    with pytest.raises(nd.BoundsError, match="do not enclose"):
        nd.pack(nd.Function(lambda p: np.linalg.norm(p, axis=1) - 1, 2, [[-0.5, -0.5], [0.5, 0.5]]), n=5)
    with pytest.raises(nd.DimensionError, match="different dimensions"):
        nd.Box([0, 0], [1, 1]) | nd.Ball([0, 0, 0], 1)
    with pytest.raises(TypeError, match="ndpack.Function"):
        nd.pack(lambda p: p, n=5)
    nan_plugin = nd.Function(
        lambda p: np.where(p[:, 0] > 0.3, np.nan, np.linalg.norm(p, axis=1) - 1), 2, [[-1, -1], [1, 1]]
    )
    with pytest.raises(nd.OracleError, match="NaN"):
        nd.pack(nan_plugin, n=5)
    with pytest.raises(nd.BackendError, match="unknown backend"):
        nd.pack(nd.Box([0, 0], [1, 1]), n=5, backend="abacus")


#: A 6-D simplex of volume 3.9e-5 (seeded draw of a fuzzing run): no centre of the default grid's
#: cells, and none of their random starts, lies inside it; it was refused as having no interior.
THIN_SIMPLEX = np.array([
    [0.590744682332728, -0.11775794013592078, -0.9184753453827712, -0.6236909925144596, -0.8186955331500825,
     -0.3333131719404434],
    [0.3687533161418852, 0.18142946380973957, 0.32425517991648145, -0.09080973815908178, -0.780438926097786,
     -0.40748808992131424],
    [0.02192095784290049, -0.005670069854692761, -0.5126772242341213, 0.6506031163337171, -0.13337332802591995,
     0.6909122503213605],
    [-0.469014739336977, 0.88387917174626, -0.7762853071975497, 0.5383649810295112, -0.9596270939805613,
     -0.5273586729169779],
    [0.7411066086203866, -0.29979000037742565, 0.8649589861175722, 0.8588340012457134, 0.6003851537870106,
     -0.20778910155036856],
    [0.7165370068719548, -0.08579132614236129, -0.7476556098287443, 0.7039167378383566, 0.6324934088437917,
     -0.7288691190953913],
    [0.7330530339569157, 0.037926106207502475, 0.4871815170243521, -0.4636479584006812, -0.5690770323567007,
     0.6966256298153561],
])


def _inradius(vertices):
    """The largest ball in a simplex, by a linear programme over its facets (independent of ndpack)."""
    from scipy.optimize import linprog

    dim, rows, limits = vertices.shape[1], [], []
    for i in range(dim + 1):
        facet = np.delete(vertices, i, axis=0)
        normal = np.linalg.svd(facet[1:] - facet[0])[2][-1]
        normal = -normal if normal @ (vertices[i] - facet[0]) > 0 else normal
        rows.append(np.r_[normal, 1.0])
        limits.append(normal @ facet[0])
    result = linprog(np.r_[np.zeros(dim), -1.0], A_ub=rows, b_ub=limits, bounds=[(None, None)] * dim + [(0, None)])
    return result.x[-1]


@pytest.mark.parametrize("mode", ["faithful", "fast"])
def test_a_shape_thinner_than_the_cells_is_found_and_packed(mode):
    """The issue's 6-D refusal: the first interior points come from a search across the boundary,
    with a warning that the grid is coarse for the shape."""
    shape = nd.Simplex(THIN_SIMPLEX)
    assert shape.volume().value < 1e-4
    with pytest.warns(nd.GridWarning, match="thinner than the grid's cells"):
        packing = nd.pack(shape, n=3, mode=mode, backend="numba")
    assert len(packing) == 3 and packing.verify().ok
    # The first sphere at least half the largest that fits, though the cells are 130 times as wide
    # (over seeds 0-7: 0.52-0.75 of it; with the host generator's restarts before, 0.52-0.87).
    assert 0.5 * _inradius(THIN_SIMPLEX) <= packing.radii[0] <= _inradius(THIN_SIMPLEX) * (1 + 1e-9)


def test_a_coarse_faithful_grid_does_not_run_out_of_room():
    """A 4-D simplex on a grid of 4: the cells near its boundary whose starts all lay outside had
    no prototype, and the faithful mode stopped at 15 of 51 spheres (no room)."""
    shape = nd.Simplex([[0.4602, 0.5821, -0.379, -0.3621], [0.8661, -0.039, -0.6904, -0.3044],
                        [-0.8081, 0.568, 0.0748, -0.0781], [-0.1044, 0.581, 0.0505, 0.1617],
                        [-0.5906, -0.6482, -0.6381, -0.98]])
    packing = nd.pack(shape, n=51, grid=4, backend="numba")
    assert len(packing) == 51 and packing.stop_reason == "count" and packing.verify().ok
