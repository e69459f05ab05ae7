"""The final check's centre distances, computed as the spheres are placed (centre_distances)."""

from pathlib import Path

import numpy as np
import pytest

import ndpack as nd
from ndpack.drivers.greedy import protosphere
from ndpack.drivers.greedy.centre_distances import CentreDistances, during_rounds

MESHES = Path(__file__).parents[2] / "data" / "meshes"


class _Spy:
    """Records the centre distances the driver's final check is given."""

    def __init__(self, monkeypatch):
        self.given = []
        verify_with = protosphere.verify_with

        def spied(packing, shape=None, *args, centre_distances=None, **kwargs):
            self.given.append(centre_distances)
            return verify_with(packing, shape, *args, centre_distances=centre_distances, **kwargs)

        monkeypatch.setattr(protosphere, "verify_with", spied)


def _shapes():
    return {
        "mesh": nd.TriangleMesh.load(MESHES / "cow.ply"),
        "csg": nd.Box([0, 0, 0], [1, 1, 1]) - nd.Ball([1, 1, 1], 0.5),
        "periodic": nd.Periodic(nd.Box([0, 0], [1, 1])),
    }


@pytest.mark.parametrize("name", ["mesh", "csg", "periodic"])
def test_distances_computed_during_the_rounds_are_the_checks_own(name, monkeypatch):
    shape = _shapes()[name]
    plain = nd.pack(shape, 300, mode="fast", backend="numba", seed=1, progress=False)
    spy = _Spy(monkeypatch)
    monkeypatch.setattr(protosphere, "during_rounds", lambda backend: True)
    packing = nd.pack(shape, 300, mode="fast", backend="numba", seed=1, progress=False)
    np.testing.assert_array_equal(packing.centers, plain.centers)
    np.testing.assert_array_equal(packing.radii, plain.radii)
    given = spy.given[0]
    assert given is not None and len(given) == len(packing)
    # Bit for bit what the check would have computed, in the packing's order.
    np.testing.assert_array_equal(given, packing.shape._distance(packing.centers))
    assert packing.verify().ok


def test_on_a_cpu_the_check_computes_them(monkeypatch):
    spy = _Spy(monkeypatch)
    packing = nd.pack(nd.Box([0, 0], [1, 1]), 50, backend="numba", progress=False)
    assert spy.given == [None] and packing.verify().ok


def test_centres_only_runs_reuse_the_distances_they_sorted_by(monkeypatch):
    # A centres-only run evaluates the user's shape at every centre to decide which count: on
    # any backend, the final check takes those values.
    spy = _Spy(monkeypatch)
    shape = nd.Box([0, 0], [1, 1])
    packing = nd.pack(shape, 100, max_radius=0.05, centers_only=True, backend="numba", progress=False)
    given = spy.given[0]
    assert given is not None
    np.testing.assert_array_equal(given, shape._distance(packing.centers))
    assert (given < 0).all() and packing.verify().ok


def test_a_sphere_placed_outside_is_still_found(monkeypatch):
    # The check's verdict does not trust the driver: a sphere that pokes out (a lying backend,
    # here a shape that shrinks after the run) is repaired from the distances computed ahead.
    monkeypatch.setattr(protosphere, "during_rounds", lambda backend: True)
    spy = _Spy(monkeypatch)
    shape = nd.Box([0, 0], [1, 1])
    insert = protosphere.RunState.insert

    def grown(self, centers, radii, round_index, counted=True):  # the first sphere 10% too large
        if self.count == 0 and counted:
            radii = radii * 1.1
        return insert(self, centers, radii, round_index, counted)

    monkeypatch.setattr(protosphere.RunState, "insert", grown)
    with pytest.warns(nd.RepairWarning):
        packing = nd.pack(shape, 20, backend="numba", progress=False, on_invalid="repair")
    assert spy.given[0] is not None
    assert packing.repair["outside"] == 1 and packing.verify().ok


def test_an_interrupted_run_is_checked_with_the_distances_of_what_it_placed(monkeypatch):
    monkeypatch.setattr(protosphere, "during_rounds", lambda backend: True)
    spy = _Spy(monkeypatch)

    def interrupted_in_the_third_round(round):
        if round.index == 2:
            raise KeyboardInterrupt

    shape = nd.Box([0, 0], [1, 1])
    packing = nd.pack(shape, 1000, mode="fast", backend="numba", on_round=interrupted_in_the_third_round,
                      progress=False)
    assert packing.stop_reason == "interrupted" and packing.verify().ok
    np.testing.assert_array_equal(spy.given[0], shape._distance(packing.centers))


def test_batches_given_and_computed_keep_their_order():
    class Sum:
        calls = 0

        def _distance(self, points):
            Sum.calls += 1
            return points.sum(axis=1)

    distances = CentreDistances(Sum(), compute=True)
    distances.add(np.ones((2, 2)))
    distances.add(np.zeros((3, 2)), known=np.full(3, 7.0))
    distances.add(np.full((1, 2), 2.0))
    distances.catch_up()
    distances.add(np.full((2, 2), 3.0))
    assert Sum.calls == 1  # the batches waiting, in one call
    np.testing.assert_array_equal(distances.collect(8), [2, 2, 7, 7, 7, 4, 6, 6])
    assert Sum.calls == 2
    np.testing.assert_array_equal(distances.collect(3), [2, 2, 7])
    not_computed = CentreDistances(Sum(), compute=False)
    not_computed.add(np.ones((2, 2)))
    assert not_computed.collect(2) is None and Sum.calls == 2


def test_a_gpu_computes_them_while_its_device_works():
    class Gpu:
        launch_bound = True

    class Cpu:
        launch_bound = False

    assert during_rounds(Gpu()) and not during_rounds(Cpu()) and not during_rounds(object())


def test_each_round_s_distances_are_computed_after_its_moves_are_queued(monkeypatch):
    # The driver asks for them once a round, after the round's work for the device: what waits
    # at the end is the last round's spheres only.
    monkeypatch.setattr(protosphere, "during_rounds", lambda backend: True)
    waiting = []
    collect = CentreDistances.collect

    def watched(self, count):
        waiting.append(sum(len(points) for _, points in self._waiting))
        return collect(self, count)

    monkeypatch.setattr(CentreDistances, "collect", watched)
    rounds = []
    packing = nd.pack(nd.Box([0, 0], [1, 1]), 500, mode="fast", backend="numba", progress=False,
                      on_round=lambda r: rounds.append(len(r.radii)))
    assert len(rounds) > 3 and waiting == [rounds[-1]] and packing.verify().ok
