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
    assert "prm[prm.shape[0] - 3 - 2 * i]" in kernels


def test_launches_are_counted_per_round(work_model):
    pytest.importorskip("warp")
    found = work_model.count_launches(nd.Box(np.zeros(3), np.ones(3)), 300, seed=0)
    assert found["spheres"] == 300 and found["rounds"] == len(found["per_round"]) > 1
    assert found["launches"] == sum(entry["launches"] for entry in found["kernels"].values())
    assert found["launches"] >= sum(entry["launches"] for entry in found["per_round"])
    assert any(name.startswith("move_ids") for name in found["kernels"]) and found["syncs"] > 0
    assert found["host_rounds_s"] > 0 and found["verify_s"] > 0 and found["split_ratio"] is not None


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
