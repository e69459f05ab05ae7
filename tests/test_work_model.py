"""bench/work_model.py counts the GPU's work on the CPU: its instrumentation still finds the kernel
lines it counts in, and its launch count follows the device store's rounds."""

import ast
import importlib.util
from pathlib import Path

import numpy as np
import pytest

import ndpack as nd
from ndpack.backends import numba_common
from ndpack.kernels.compiled import compiled_program

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def work_model():
    spec = importlib.util.spec_from_file_location("work_model", ROOT / "bench" / "work_model.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_counters_go_where_the_walks_are(work_model):
    """A kernel change that moves the lines the counters hook on fails here, not in a GPU session."""
    mesh = nd.TriangleMesh.load(ROOT / "tests" / "data" / "meshes" / "cow.ply")
    program = work_model.counting_nodes(compiled_program(mesh).program.source("numba"))
    kernels = work_model.counting_prototypes(numba_common.KERNELS + numba_common.ENTRIES)
    for text in (program, kernels):
        ast.parse(text)
    # Every walk of the tree counts: the nearest element's, and the winding number's where it walks.
    assert program.count("prm[prm.shape[0] - 1] += 1.0") == program.count("node = pending[top]\n") >= 1
    assert kernels.count("prm[prm.shape[0] - 2] += 1.0") == 1
    # The cooperative rounds: counted once a nearest-element query, and three counts a prototype.
    assert program.count("prm[prm.shape[0] - 3] += lanes_walk(q, prm, o, limit, 32)[1]") == 1
    assert "def lanes_walk(" in kernels
    for slot in ("4 - 3 * i", "5 - 3 * i", "6 - 3 * i"):
        assert f"prm[prm.shape[0] - {slot}]" in kernels


def test_cooperative_rounds_are_counted_beside_the_nodes(work_model):
    """The walks' instrumented run on a small mesh: a cooperative launch's rounds, fewer than the
    nodes of its slowest prototype's walks (32 lanes; the deepest query of a small tree still
    visits more nodes than the tree is deep)."""
    mesh = nd.TriangleMesh.load(ROOT / "tests" / "data" / "meshes" / "cow.ply")
    found = work_model.count_walks(mesh, 200, seed=0, most_points=200_000)
    launches = found["launches"]
    assert found["spheres"] == 200 and all(launch["cooperative"] for launch in launches
                                            if 0 < launch["prototypes"] <= 4096)
    walked = [launch for launch in launches if launch["steps"] and launch["most_nodes"] > 0]
    assert walked and all(0 < launch["most_rounds"] < launch["most_nodes"] for launch in walked)
    assert found["cooperative_critical_rounds"] == sum(launch["most_rounds"] for launch in launches
                                                       if launch["cooperative"])


def test_hard_first_puts_the_chosen_walks_in_cooperative_blocks(work_model):
    """The critical path of a launch whose K hardest prototypes walk cooperatively: the longest of
    the rest, or the chosen ones' longest over the rounds a cooperative walk saves."""
    nodes = np.array([10.0, 5000.0, 40.0, 300.0, 20.0])
    wall = np.array([0.1, 0.9, 0.2, 0.3, 0.0])  # the shallowest cell is not the hardest walk here
    found = work_model.hard_first(nodes, wall)
    assert found["oracle_256"] == pytest.approx(5000.0 / work_model.NODES_PER_ROUND)  # every one cooperative
    assert found["shallowest_256"] == found["oracle_256"]
    one = work_model.hard_first(nodes, wall, ks=(1,))
    assert one["oracle_1"] == 300.0  # the hardest out of the way: the next is the path
    assert one["shallowest_1"] == 5000.0  # the shallowest cell was an easy walk


def test_launches_are_counted_per_round(work_model):
    pytest.importorskip("warp")
    found = work_model.count_launches(nd.Box(np.zeros(3), np.ones(3)), 300, seed=0)
    assert found["spheres"] == 300 and found["rounds"] == len(found["per_round"]) > 1
    assert found["launches"] == sum(entry["launches"] for entry in found["kernels"].values())
    assert found["launches"] >= sum(entry["launches"] for entry in found["per_round"])
    assert any(name.startswith("move_ids") for name in found["kernels"]) and found["syncs"] > 0
    # Every synchronisation is put down to the store's method that made it (the window's, the touched's, ...).
    assert sum(found["syncs_by_method"].values()) == found["syncs"]
    assert any(site.startswith("window (from choose)") for site in found["syncs_by_method"])
    # The host's and the check's times are recorded (their size is bench's business, not a test's).
    assert {"host_rounds_s", "verify_s"} <= found.keys()
    assert found["split_ratio"] is not None


def test_the_host_is_predicted_from_its_own_time(work_model):
    """With a GPU run's stages, the host's rounds and the final check are predicted from this
    machine's times of them, scaled as the GPU run's were; without, by synchronisations."""
    counted = dict(kernels={"move_ids[move+ahead]": dict(launches=10), "select_all": dict(launches=30)},
                   launches=40, syncs=20, host_rounds_s=0.5, verify_s=0.2)
    result = dict(launches=counted, walks=dict(critical_path_nodes=1e5))
    kernels = {"move_ids[move+ahead]": [10, 0.8], "select_all": [30, 0.2]}
    profile = {"warp": dict(median=2.0, device=1.0, kernels=kernels, stages=dict(setup=0.1, rounds=1.6, verify=0.3))}
    constants = work_model.against(result, profile)
    assert constants["same_launches"] and constants["host_over_cpu"] == pytest.approx(1.2)
    assert constants["verify_over_cpu"] == pytest.approx(1.5) and constants["setup_s"] == 0.1
    found = work_model.predict(result, constants)
    assert found["moves"] == pytest.approx(0.8) and found["other_launches"] == pytest.approx(0.2)
    assert found["host"] == pytest.approx(0.6) and found["verify"] == pytest.approx(0.3)
    assert found["seconds"] == pytest.approx(0.8 + 0.2 + 0.6 + 0.3 + 0.1)
    del profile["warp"]["stages"]
    older = work_model.predict(result, work_model.against(result, profile))
    assert "verify" not in older and older["host"] == pytest.approx(1.0)  # 20 syncs of (2.0 - 1.0) / 20 s


def test_cooperative_moves_take_a_node_and_a_round_constant(work_model):
    """A run with cooperative walks and its lanes-off variant: a serial node's seconds from the
    variant, a cooperative round's from the rest of the run's move time; the prediction adds both."""
    counted = dict(kernels={"move_ids[move+ahead]": dict(launches=10), "select_all": dict(launches=5)}, launches=15,
                   syncs=5)
    walks = dict(critical_path_nodes=1e5, serial_critical_nodes=2e4, cooperative_critical_rounds=1e4)
    result = dict(launches=counted, walks=walks)
    now = dict(median=1.0, device=0.6, kernels={"move_ids[move+ahead]": [10, 0.5], "select_all": [5, 0.1]})
    off = dict(median=2.0, device=1.2, kernels={"move_ids[move+ahead]": [10, 1.0], "select_all": [5, 0.1]})
    constants = work_model.against(result, {"warp now": now, "warp lanes-off": off})
    assert constants["seconds_per_critical_node"] == pytest.approx(1e-5)  # 1.0 s over 1e5 nodes
    assert constants["seconds_per_critical_round"] == pytest.approx((0.5 - 2e4 * 1e-5) / 1e4)
    assert work_model.predict(result, constants)["moves"] == pytest.approx(0.5)
