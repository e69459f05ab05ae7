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
from ndpack.io.named_shapes import from_spec
from ndpack.errors import BackendError, KernelError, ShapeError

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parents[2] / "examples"))
from gyroid_5d import gyroid  # the example of the docs is what we test


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


@pytest.mark.parametrize(
    "name",
    [n for n in _installed() if n != "numba-cuda" or not __import__("os").environ.get("NUMBA_ENABLE_CUDASIM")],
)
def test_gyroid_packs_on_every_backend(name):
    packing = nd.pack(gyroid, 30, grid=6, backend=name)
    assert packing.params["backend"] == name
    assert len(packing.radii) == 30
    assert packing.verify().ok
    reference = nd.pack(gyroid, 30, grid=6, backend="numpy")
    assert abs(packing.fill - reference.fill) <= 0.01 * reference.fill


def _compile(source):
    namespace = {"math": math}
    exec(textwrap.dedent(source), namespace)  # the test needs a function object
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
    # A lambda in a file has a source line, but no function definition: the hint is still def.
    with pytest.raises(KernelError, match="cannot be a lambda: define it with def"):
        nd.ScalarFunction(lambda_in_a_file, 2, [[-1, -1], [1, 1]])
    with pytest.raises(ShapeError, match="bounds"):
        nd.scalar_plugin(dim=2)(ring)


def lambda_free_three_args(p, params, extra):
    return p[0]


lambda_in_a_file = lambda p, params: p[0] - params[0]  # noqa: E731  (what the test is about)


def _module(tmp_path, name, text):
    """Import ``text`` as the module ``name`` from a file in ``tmp_path``."""
    (tmp_path / f"{name}.py").write_text(textwrap.dedent(text))
    sys.path.insert(0, str(tmp_path))
    try:
        sys.modules.pop(name, None)
        return __import__(name)
    finally:
        sys.path.remove(str(tmp_path))
        sys.modules.pop(name, None)


def test_messages_give_the_line_in_the_users_file(tmp_path):
    """Comments and blank lines count: the line is the file's, the name the function's own."""
    module = _module(tmp_path, "commented_plugins", """\
        import math


        # A comment above the function.
        def shell(p, params):
            # a comment

            r = math.sqrt(p[0] * p[0] + p[1] * p[1])

            # another one
            return sum(p) - r


        def bare(p, params):
            \"\"\"A docstring.\"\"\"

            x = params
            return p[0]
        """)
    where = tmp_path / "commented_plugins.py"
    with pytest.raises(KernelError) as error:
        nd.ScalarFunction(module.shell, 2, [[-1, -1], [1, 1]])
    assert str(error.value).startswith(f"kernel 'shell', line 11 of {where}: unknown function 'sum'")
    with pytest.raises(KernelError) as error:
        nd.ScalarFunction(module.bare, 2, [[-1, -1], [1, 1]])
    assert str(error.value).startswith(f"kernel 'bare', line 17 of {where}: use the parameters only by index")


@pytest.mark.parametrize(
    "body, message",
    [
        ("return p[2]",
         "line 5 of .*index 2 is out of range: the point 'p' has D = 2 coordinates, p\\[0\\] to p\\[1\\]"),
        ("return p[D]", "index 2 is out of range"),
        ("return p[-1]", "negative index -1: .*write p\\[D - 1\\]"),
        ("return p[0] + params[2]",
         "params\\[2\\] is out of range: there are 2 params, params\\[0\\] to params\\[1\\]"),
        ("return p[0] + params[-1]", "params\\[-1\\] is out of range"),
        ("q = point()\n    q[D - 1 + 1] = 1.0\n    return q[0]",
         "line 6 of .*index 2 is out of range: the local point 'q'"),
        ("s = stack()\n    s[64] = 1\n    return 0.0", "index 64 is out of range: the stack 's' has 64 entries"),
        ("if p[0] > 0.0:\n        return 1.0", "line 5 of .*ends here without return; every path must return a number"),
        ("for i in range(D):\n        return p[i]", "ends here without return"),
        ("x = p[0]\n    if x > 0.0:\n        return x\n    elif x < -0.5:\n        return -x",
         "line 6 of .*ends here without return"),
    ],
)
def test_bad_indices_and_missing_returns_are_refused(tmp_path, body, message):
    module = _module(tmp_path, "bad_index", f"import math\n\n\ndef bad(p, params):\n    {body}\n")
    with pytest.raises(KernelError, match=message):
        nd.ScalarFunction(module.bad, 2, [[-1, -1], [1, 1]], params=[0.5, 0.9])


def in_range(p, params):
    """Indices that stay inside: from the end through D, a loop, every path returning."""
    s = p[D - 1] + params[D - 1] + params[0]  # noqa: F821  (D is the dimension)
    q = point()  # noqa: F821
    for i in range(D):  # noqa: F821
        q[i] = p[i]
    while True:
        if s > 10.0:
            return s
        s += q[0] * q[0] + 1.0


def test_indices_in_range_and_returning_loops_are_accepted():
    shape = nd.ScalarFunction(in_range, 2, [[-1, -1], [1, 1]], params=[0.5, 0.25])
    assert shape.distance(np.zeros((1, 2)))[0] == pytest.approx(10.75)


def test_numpy_plugin_on_a_compiled_backend_says_what_to_do():
    disc = nd.Function(lambda p: np.linalg.norm(p, axis=1) - 1.0, 2, [[-1, -1], [1, 1]])
    with pytest.raises(BackendError, match="ScalarFunction"):
        nd.pack(disc, 2, backend="numba")


def test_entry_point_shapes_are_found(monkeypatch):
    import ndpack.io.named_shapes as named_shapes

    entry = EntryPoint(name="ring", value="tests_ring_factory:make", group=named_shapes.ENTRY_POINT_GROUP)
    fake = type(sys)("tests_ring_factory")
    fake.make = lambda inner=0.3: nd.ScalarFunction(ring, 2, [[-1, -1], [1, 1]], params=[inner, 0.9])
    monkeypatch.setitem(sys.modules, "tests_ring_factory", fake)
    monkeypatch.setattr("importlib.metadata.entry_points",
                        lambda group: [entry] if group == named_shapes.ENTRY_POINT_GROUP else [])
    shape = from_spec("ring:inner=0.5")
    assert shape.params.tolist() == [0.5, 0.9]
    assert "ring" in named_shapes.registered()
    with pytest.raises(ShapeError, match="known shapes are: .*ring"):
        from_spec("no_such_shape")


# ---------------------------------------------------------------------- arithmetic on every backend
def arithmetic(p, params):
    """Python's //, % and ** on ints, floats and both, chosen by p[0] for operands p[1], p[2]."""
    case = int(p[0])
    a = p[1]
    b = p[2]
    i = int(a)
    j = int(b)
    if case == 0:
        return float(i % j)
    if case == 1:
        return float(i // j)
    if case == 2:
        return a % b
    if case == 3:
        return a // b
    if case == 4:
        return float(i ** j)  # an int ** an int, negative exponents too
    if case == 5:
        return a ** j
    if case == 6:
        return i % b + 100.0 * (a // j)
    if case == 7:
        x = i
        x %= j
        y = i
        y //= j
        return float(x) + 1000.0 * float(y)
    if case == 8:
        x = a
        x %= b
        y = a
        y //= b
        return x + 1000.0 * y
    if case == 9:
        z = j
        z **= 2
        return z - 0.5
    k = int(p[0] * 0 + 3)
    return float(k ** 2) - 10.0


INT_PAIRS = [(-8, 3), (8, -3), (-8, -3), (8, 3), (-7, 2), (0, 5), (6, -3), (-1, 4), (-2, -1)]
#: Floats with exact binary values (float32 agrees), then decimals where // and % differ most.
FLOAT_PAIRS = [(-7.5, 3.0), (7.5, -3.0), (-7.5, -2.0), (5.25, 0.5), (-0.75, 4.0), (-3.0, 1.5)]
DECIMAL_PAIRS = [(1.0, 0.1), (-1.0, 0.1), (0.3, -0.1), (-1e-30, 3.0), (2.0, 0.2)]


def _arithmetic_points(decimals=True):
    float_pairs = FLOAT_PAIRS + (DECIMAL_PAIRS if decimals else [])
    rows = [(case, a, b) for case in (0, 1, 4, 7, 9) for a, b in INT_PAIRS]
    rows += [(case, a, b) for case in (2, 3, 5, 6, 8) for a, b in float_pairs if int(b) != 0 or case in (2, 3, 8)]
    rows += [(10, 0.0, 0.0)]
    return np.array(rows, dtype=np.float64)


def _python(fn, points, params=()):
    """``fn`` run by Python itself, one point at a time (on Python floats)."""
    return np.array([fn([float(x) for x in point], list(params)) for point in points])


def test_arithmetic_follows_python_on_every_backend():
    """``//`` and ``%`` round down and take the divisor's sign, ``**`` is a float (``2 ** -1`` is
    0.5), for ints and floats, on numba and warp (float64 and float32) and numba-cuda where it runs."""
    shape = nd.ScalarFunction(arithmetic, 3, [[-1, -1, -1], [1, 1, 1]])
    points = _arithmetic_points()
    expected = _python(arithmetic, points)
    assert expected[(points[:, 0] == 3) & (points[:, 1] == 1.0) & (points[:, 2] == 0.1)] == 9.0  # 1.0 // 0.1
    runs = [("numba", {}, points)]
    if "warp" in _installed():
        runs += [("warp", {}, points), ("warp", {"precision": "float32"}, _arithmetic_points(decimals=False))]
    if "numba-cuda" in _installed():
        runs.append(("numba-cuda", {}, points))
    for name, options, where in runs:
        got = backends.get_backend(name, **options).distance(shape, where)
        want = _python(arithmetic, where)
        tolerance = 1e-6 if options else 1e-14
        np.testing.assert_allclose(got, want, rtol=tolerance, atol=tolerance, err_msg=f"{name} {options}")
        assert np.array_equal(np.signbit(got[want != 0]), np.signbit(want[want != 0])), name
    np.testing.assert_array_equal(shape.distance(points), expected)  # the numba CPU form, exactly


# ---------------------------------------------------------------------- several plug-ins in one tree
def test_one_function_with_other_params_in_one_tree_compiles_once(monkeypatch):
    from ndpack.kernels.compiled import has_kernel
    from ndpack.kernels import build

    small = nd.ScalarFunction(ring, 2, [[-1, -1], [1, 1]], params=[0.2, 0.4])
    large = nd.ScalarFunction(ring, 2, [[-1, -1], [1, 1]], params=[0.6, 0.9])
    shape = small | large.translate([0.3, 0.0])
    program = build(shape)
    assert [name for name in program.kernels if "ring" in name] == ["user_ring"]
    assert has_kernel(shape)
    monkeypatch.delenv("NDPACK_BACKEND")
    assert backends.get_backend(shape=shape).name != "numpy"  # left to choose, it compiles
    points = np.random.default_rng(2).uniform(-1, 1, (200, 2))
    shifted = points - [0.3, 0.0]
    expected = np.minimum(_python(ring, points, small.params), _python(ring, shifted, large.params))
    np.testing.assert_allclose(shape.distance(points), expected, atol=1e-15)
    np.testing.assert_allclose(backends.get_backend("numba").distance(shape, points), expected, atol=1e-15)


def test_two_functions_of_one_name_get_two_kernels(tmp_path):
    first = _module(tmp_path, "shapes_a", """\
        def f(p, params):
            return abs(p[0]) - params[0]
        """).f
    second = _module(tmp_path, "shapes_b", """\
        def f(p, params):
            return abs(p[1]) - params[0]
        """).f
    a = nd.ScalarFunction(first, 2, [[-1, -1], [1, 1]], params=[0.5])
    b = nd.ScalarFunction(second, 2, [[-1, -1], [1, 1]], params=[0.25])
    again = nd.ScalarFunction(first, 2, [[-1, -1], [1, 1]], params=[0.125])
    shape = a & b & again.translate([0.1, 0.0])
    from ndpack.kernels import build

    assert [name for name in build(shape).kernels if name.startswith("user_")] == ["user_f", "user_f_2"]
    points = np.random.default_rng(3).uniform(-1, 1, (100, 2))
    expected = np.maximum.reduce([_python(first, points, [0.5]), _python(second, points, [0.25]),
                                  _python(first, points - [0.1, 0.0], [0.125])])
    np.testing.assert_allclose(shape.distance(points), expected, atol=1e-15)
