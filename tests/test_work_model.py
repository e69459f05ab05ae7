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
