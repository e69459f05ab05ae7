"""Device kernels written once (ndpack.kernels.portable): printed for numba-cuda and Warp, and refused
where the two would mean different things."""

from __future__ import annotations

import ast
import textwrap
from pathlib import Path

import numpy as np
import pytest

from ndpack.errors import KernelError
from ndpack.kernels.portable import ARGUMENT_TYPES, kernel_names, render

SOURCE = textwrap.dedent('''
    def nearest_side(i: "int", lower: "points", upper: "points"):
        """The shortest side of box i and its axis."""
        side = upper[i, 0] - lower[i, 0]
        axis = 0
        for k in range(1, D):
            if upper[i, k] - lower[i, k] < side:
                side = upper[i, k] - lower[i, k]
                axis = k
        return side, axis


    def spread(g: "point", v: "float"):
        for k in range(D):
            g[k] = v * float(k)


    def through(x: "point", g: "point", v: "float"):
        """Writes g through spread (so Warp returns it); reads x."""
        spread(g, v)
        return x[0] + g[1]


    def boxes(count: "int", lower: "points", upper: "points", scale: "float", out: "floats", axes: "ints",
              total: "ints", most: "floats"):
        i = thread()
        if i < count:
            side, axis = nearest_side(i, lower, upper)
            centre = point()
            for k in range(D):
                centre[k] = 0.5 * (lower[i, k] + upper[i, k])
            far = math.sqrt(centre[0] * centre[0]) if side > 0.25 else -math.inf
            if side < 0.0:
                far = math.nan
            out[i] = max(far, scale * float(axis), -1.0) + min(side, 2.0, 3.0)
            axes[i] = axis
            for k in range(axis):
                weight = float(k)  # Warp's cast of a bare name would retype k: lower[i, k] would fail
                out[i] += 0.0 * weight * lower[i, k]
            upper[i, axis] = upper[i, axis] + 1.0
            atomic_add(total, 0, 1)
            atomic_max(most, 0, side)
            scratch = point()
            back = through(centre, scratch, 0.5)
            out[i] += back - centre[0] - 0.5 + scratch[2] - 1.0  # 0 where scratch came back written
''')


def test_warp_print_types_the_arguments_and_casts_what_warp_does_not_promote():
    text = render(SOURCE, "warp")
    tree = ast.parse(text)
    nearest, spread, through, boxes = tree.body
    assert [ast.unparse(d) for d in nearest.decorator_list] == ["wp.func"]
    assert [ast.unparse(d) for d in boxes.decorator_list] == ["wp.kernel"]
    assert [ast.unparse(a.annotation) for a in boxes.args.args] == [
        "int", ARGUMENT_TYPES["points"], ARGUMENT_TYPES["points"], "F", ARGUMENT_TYPES["floats"],
        ARGUMENT_TYPES["ints"], ARGUMENT_TYPES["ints"], ARGUMENT_TYPES["floats"]]
    for printed in ("i = wp.tid()", "upper[i][0] - lower[i][0]", "centre = VecD()", "F(0.5) * (lower[i][k]",
                    "wp.where(side > F(0.25), wp.sqrt(centre[0] * centre[0]), -F(wp.inf))",
                    "wp.max(wp.max(far, scale * F(+axis)), -F(1.0))", "wp.min(wp.min(side, F(2.0)), F(3.0))",
                    "upper[i][axis] = upper[i][axis] + F(1.0)", "F(+k)", "F(wp.nan)", "axis = int(0)",
                    "wp.atomic_add(total, 0, 1)",
                    "wp.atomic_max(most, 0, side)", '"""The shortest side of box i and its axis."""',
                    # A point written in a function comes back to its caller, as in Numba.
                    "return g", "    g = spread(g, v)", "return (x[0] + g[1], g)",
                    "back, scratch = through(centre, scratch, F(0.5))"):
        assert printed in text, printed
    assert "math." not in text and "thread" not in text


def test_cuda_print_keeps_numba_s_dialect():
    text = render(SOURCE, "cuda")
    tree = ast.parse(text)
    assert all(a.annotation is None for f in tree.body for a in f.args.args)
    for printed in ("i = cuda.grid(1)", "upper[i, 0] - lower[i, 0]", "centre = point()", "0.5 * (lower[i, k]",
                    "math.sqrt(", "-math.inf", "float(axis)", "cuda.atomic.add(total, 0, 1)",
                    "cuda.atomic.max(most, 0, side)"):
        assert printed in text, printed
    assert kernel_names(SOURCE) == ["boxes"]


def test_warp_print_runs_as_the_numbers_say():
    """The printed kernel compiles in a Warp module and computes what the source says."""
    wp = pytest.importorskip("warp")
    from ndpack.kernels.compile import _import_generated

    wp.init()
    if not wp.is_cpu_available():
        pytest.skip("Warp's CPU compiler is not available here")

    header = ("import warp as wp\nwp.set_module_options({'enable_backward': False})\nF = wp.float64\nD = 3\n"
              "VecD = wp.types.vector(length=3, dtype=wp.float64)\n\n\n")
    module = _import_generated(header + render(SOURCE, "warp"), "warp")
    rng = np.random.default_rng(3)
    lower = rng.random((6, 3))
    upper = lower + rng.random((6, 3)) * 0.6
    arrays = dict(lower=wp.array(lower, dtype=module.VecD, device="cpu"),
                  upper=wp.array(upper, dtype=module.VecD, device="cpu"),
                  out=wp.zeros(6, dtype=wp.float64, device="cpu"), axes=wp.zeros(6, dtype=wp.int32, device="cpu"),
                  total=wp.zeros(1, dtype=wp.int32, device="cpu"), most=wp.zeros(1, dtype=wp.float64, device="cpu"))
    wp.launch(module.boxes, dim=8, inputs=[6, arrays["lower"], arrays["upper"], 0.25, arrays["out"], arrays["axes"],
                                           arrays["total"], arrays["most"]], device="cpu")
    sides = upper - lower
    axis = np.argmin(sides, axis=1)  # the first of equals, as the loop keeps
    side = sides[np.arange(6), axis]
    centre = 0.5 * (lower + upper)
    far = np.where(side > 0.25, np.abs(centre[:, 0]), -np.inf)
    expected = np.maximum(np.maximum(far, 0.25 * axis), -1.0) + np.minimum(side, 2.0)
    np.testing.assert_array_equal(arrays["axes"].numpy(), axis)
    np.testing.assert_allclose(arrays["out"].numpy(), expected, rtol=1e-15, atol=1e-15)
    assert arrays["total"].numpy()[0] == 6 and arrays["most"].numpy()[0] == side.max()
    moved = upper.copy()
    moved[np.arange(6), axis] += 1.0
    np.testing.assert_array_equal(arrays["upper"].numpy(), moved)


@pytest.mark.parametrize("body, message", [
    ('def f(i, x: "floats"):\n    return x[i]\n', "argument 'i' needs one of the types"),
    ('def f(i: "int", x: "whatever"):\n    return i\n', "argument 'x' needs one of the types"),
    ('def g(p: "point"):\n    p[0] = 1.0\n\n\ndef f(x: "floats"):\n    q = point()\n    return x[0] + g(q)\n',
     "call it as a statement"),
    ('def g(p: "point"):\n    p[0] = 1.0\n\n\ndef f(x: "points"):\n    g(x)\n    return 0.0\n', "pass them as names"),
    ('def g(p: "point", q: "point"):\n    p[0] = q[0]\n    q[0] = 1.0\n\n\ndef f(x: "floats"):\n    q = point()\n'
     '    g(q, q)\n    return x[0]\n', "one point twice"),
    ('def f(p: "point", q: "point"):\n    p = q\n    return 0.0\n', "assigned whole"),
    ('def f(x: "floats"):\n    p = point()\n    q = p\n    return q[0]\n', "assigned whole"),
    ('def f(p: "point"):\n    q = p\n    return q[0]\n', "assigned whole"),
    ('def f(x: "floats"):\n    return g(x)[0]\n', "unpack a call's results"),
    ('def f(x: "floats"):\n    i = thread()\n    return x[i]\n', "a kernel returns nothing"),
    ('def f(x: "ints"):\n    i = cuda.grid(1)\n    x[i] = 0\n', "a backend's own"),
])
def test_what_would_differ_between_the_backends_is_refused_with_its_place(body, message):
    for dialect in ("cuda", "warp"):
        with pytest.raises(KernelError, match=message) as error:
            render(body, dialect)
        assert "portable kernel 'f', line" in str(error.value) or "portable kernel 'g', line" in str(error.value)


def test_an_unknown_dialect_is_refused():
    with pytest.raises(KernelError, match="dialect"):
        render(SOURCE, "opencl")


def test_the_kernels_are_written_once():
    """Every compiled backend runs the printed move, index and store kernels; none keeps its own copy,
    and each backend's text defines each of them once."""
    from ndpack.backends import kernel_texts, numba_common, numba_cuda_backend
    from ndpack.backends.warp_backend import KERNELS as WARP

    folder = Path(kernel_texts.__file__).parent
    own = {"warp": (folder / "warp_kernels.py").read_text(), "numba": (folder / "numba_kernels.py").read_text(),
           "numba-cuda": numba_cuda_backend.MOVE_ENTRY}
    printed = {"warp": WARP, "numba": numba_common.KERNELS, "numba-cuda": numba_cuda_backend.kernels_text("")}
    for name in (kernel_texts.MOVE, kernel_texts.INDEX, kernel_texts.STORE):
        functions = [f for f in ast.parse((folder / name).read_text()).body if isinstance(f, ast.FunctionDef)]
        assert len(functions) >= 5
        for function in functions:
            for backend in own:
                assert f"def {function.name}(" not in own[backend], (backend, function.name)
                if name != kernel_texts.STORE or backend != "numba":  # the CPU runs no store kernels
                    assert printed[backend].count(f"def {function.name}(") == 1, (backend, function.name)
    store = kernel_texts.portable_text(kernel_texts.STORE)
    assert set(kernel_names(store)) <= set(numba_cuda_backend.ENTRY_NAMES)
