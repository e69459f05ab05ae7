"""Scalar plug-ins: written once, checked against the kernel subset, run on every backend."""

from __future__ import annotations

import math
import sys
import textwrap
from importlib.metadata import EntryPoint

import numpy as np
import pytest

import ndpack as nd
from ndpack import backends
from ndpack.builtin import from_spec
from ndpack.errors import BackendError, KernelError, ShapeError

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parents[1] / "examples"))
from gyroid_5d import gyroid  # noqa: E402  (the example of the docs is what we test)


def _installed():
    names = []
    for name in ("numpy", "numba", "warp", "numba-cuda"):
        try:
            backends.get_backend(name)
            names.append(name)
        except BackendError:
            pass
    return names


def ring(p, params):
    """An annulus of radii params[0] < params[1], exact."""
    r = math.sqrt(p[0] * p[0] + p[1] * p[1])
    return max(params[0] - r, r - params[1])


def test_scalar_plugin_matches_numpy_formula():
    shape = nd.ScalarFunction(ring, 2, [[-1, -1], [1, 1]], params=[0.3, 0.9], exact_inside=True)
    points = np.random.default_rng(0).uniform(-1, 1, (500, 2))
    radius = np.linalg.norm(points, axis=1)
    np.testing.assert_allclose(shape.distance(points), np.maximum(0.3 - radius, radius - 0.9), atol=1e-15)
    assert shape.check_lipschitz() <= 1 + 1e-9
    assert "annulus" in shape.__doc__


def test_gyroid_example_is_conservative_and_matches_python():
    points = np.random.default_rng(1).uniform(-1, 1, (200, 5))
    k, t = gyroid.params
    s = sum(np.sin(k * points[:, i]) * np.cos(k * points[:, (i + 1) % 5]) for i in range(5))
    expected = np.maximum((np.abs(s) - t) / (k * math.sqrt(10)), np.linalg.norm(points, axis=1) - 1)
    np.testing.assert_allclose(gyroid.distance(points), expected, atol=1e-12)
    assert gyroid.check_lipschitz(samples=2000) <= 1 + 1e-6


@pytest.mark.parametrize("name", [n for n in _installed() if n != "numba-cuda" or not __import__("os").environ.get("NUMBA_ENABLE_CUDASIM")])
def test_gyroid_packs_on_every_backend(name):
    packing = nd.pack(gyroid, 30, grid=6, backend=name)
    assert packing.params["backend"] == name
    assert len(packing.radii) == 30
    assert packing.verify().ok
    reference = nd.pack(gyroid, 30, grid=6, backend="numpy")
    assert abs(packing.fill - reference.fill) <= 0.01 * reference.fill


def _compile(source):
    namespace = {"math": math}
    exec(textwrap.dedent(source), namespace)  # noqa: S102 - the test needs a function object
    return namespace


@pytest.mark.parametrize(
    "body, message",
    [
        ("return np.linalg.norm(p) - 1.0", "only math"),
        ("return sum(p) - 1.0", "unknown function 'sum'"),
        ("x = [1.0, 2.0]\n    return x[0]", "List is not supported"),
        ("return p[0:2] - 1.0", "slices"),
        ("return params - 1.0", "only by index"),
        ("return 'far'", "not a number"),
    ],
)
def test_outside_the_subset_is_a_clear_error(tmp_path, body, message):
    module = tmp_path / "bad_plugin.py"
    module.write_text(f"import math\n\ndef bad(p, params):\n    {body}\n")
    sys.path.insert(0, str(tmp_path))
    try:
        bad = __import__("bad_plugin").bad
        with pytest.raises(KernelError, match=message):
            nd.ScalarFunction(bad, 2, [[-1, -1], [1, 1]])
    finally:
        sys.path.remove(str(tmp_path))
        sys.modules.pop("bad_plugin", None)


def test_wrong_signature_and_lambda_are_clear_errors():
    with pytest.raises(KernelError, match="exactly two arguments"):
        nd.ScalarFunction(lambda_free_three_args, 2, [[-1, -1], [1, 1]])
    with pytest.raises(KernelError, match="lambda"):
        nd.ScalarFunction(_compile("f = lambda p, params: p[0]")["f"], 2, [[-1, -1], [1, 1]])
    with pytest.raises(ShapeError, match="bounds"):
        nd.scalar_plugin(dim=2)(ring)


def lambda_free_three_args(p, params, extra):
    return p[0]


def test_numpy_plugin_on_a_compiled_backend_says_what_to_do():
    disc = nd.Function(lambda p: np.linalg.norm(p, axis=1) - 1.0, 2, [[-1, -1], [1, 1]])
    with pytest.raises(BackendError, match="ScalarFunction"):
        nd.pack(disc, 2, backend="numba")


def test_entry_point_shapes_are_found(monkeypatch):
    import ndpack.builtin as builtin

    entry = EntryPoint(name="ring", value="tests_ring_factory:make", group=builtin.ENTRY_POINT_GROUP)
    fake = type(sys)("tests_ring_factory")
    fake.make = lambda inner=0.3: nd.ScalarFunction(ring, 2, [[-1, -1], [1, 1]], params=[inner, 0.9])
    monkeypatch.setitem(sys.modules, "tests_ring_factory", fake)
    monkeypatch.setattr("importlib.metadata.entry_points", lambda group: [entry] if group == builtin.ENTRY_POINT_GROUP else [])
    shape = from_spec("ring:inner=0.5")
    assert shape.params.tolist() == [0.5, 0.9]
    assert "ring" in builtin.registered()
    with pytest.raises(ShapeError, match="known shapes are: .*ring"):
        from_spec("no_such_shape")
