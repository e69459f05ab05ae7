"""Scalar kernels against the NumPy oracles: every shape and CSG node, in every dimension it has.

Each shape is compiled both ways the backends run it, with Numba (``numba_evaluator``), and
compared with the shape's own ``_distance`` at points sampled inside and around its bounds; both
compute the same formula, so they agree to rounding:

- as a tape (:mod:`ndpack.kernels.tape`, the default): its numbers for the interpreter of its
  dimension, compiled once per dimension for every shape;
- as a specialised program (:func:`ndpack.kernels.build`, the opt-in and the fallback for deep
  trees). Numba compiles each distinct program text once (about half a second), so these tests
  reuse structures: the shapes (or CSG nodes) of one dimension are compiled together behind a
  test-only selector node, and further random instances with the same structure reuse that
  program. Torus, Polygon and the nested trees are built and compiled on their own.
"""

from __future__ import annotations

import numpy as np
import pytest

import ndpack as nd
from ndpack.errors import KernelError
from ndpack.kernels import build
from ndpack.kernels.compile import numba_evaluator
from ndpack.kernels.tape import flatten
from ndpack.oracle import Oracle

pytest.importorskip("numba")

DIMS = [2, 3, 4, 5, 6]
N_POINTS = 300
#: Agreement asked for, relative to the shape's scale.
TOLERANCE = 1e-9
#: Half-width of the window sampled along axes where a shape is unbounded.
WINDOW = 3.0


# ---------------------------------------------------------------------- helpers
def sample_points(shape: Oracle, rng: np.random.Generator, count: int = N_POINTS) -> np.ndarray:
    """Points in a box a bit larger than the bounds, half of them in its middle half (mostly inside)."""
    lower, upper = shape.bounds
    lower = np.where(np.isfinite(lower), lower, -WINDOW)
    upper = np.where(np.isfinite(upper), upper, WINDOW)
    middle, half = (lower + upper) / 2, (upper - lower) / 2
    wide = middle + 1.25 * half * rng.uniform(-1, 1, (count - count // 2, shape.dim))
    centre, spread = middle, 0.5 * half
    if isinstance(shape, nd.ConvexPolytope):  # thin simplices hardly meet the middle half
        centre, spread = shape.chebyshev_center, 2 * shape.chebyshev_radius
    near = centre + spread * rng.uniform(-1, 1, (count // 2, shape.dim))
    return np.vstack([wide, near])


def compare(shape: Oracle, rng: np.random.Generator, program=None, prm=None, evaluate=None, label=""):
    """Assert that the compiled kernel of ``shape`` matches its NumPy oracle, inside and outside.

    ``program``, ``prm`` and ``evaluate`` may be given to reuse a build (the selector tests);
    ``label`` starts the failure messages. Returns the program.
    """
    if program is None:
        program = build(shape)
        prm = program.param_array()
        evaluate = numba_evaluator(program)
    points = sample_points(shape, rng)
    want = shape._distance(points)
    got = evaluate(points, prm)
    assert np.any(want < 0) and np.any(want > 0), f"{label} {shape!r}: sample points all on one side"
    error = np.abs(got - want).max()
    assert error <= TOLERANCE * shape.scale, f"{label} {shape!r}: kernel differs from NumPy by {error:.3g}"
    flat = flatten(shape)
    error = np.abs(tape_evaluator(flat.program)(points, flat.params) - want).max()
    assert error <= TOLERANCE * shape.scale, f"{label} {shape!r}: its tape differs from NumPy by {error:.3g}"
    # Every dialect prints (Warp and CUDA are not compiled here: that needs their toolchains).
    for dialect in ("warp", "cuda"):
        assert "def sd(" in program.source(dialect)
    return program


_tape_evaluators = {}


def tape_evaluator(program):
    """The compiled evaluator of an interpreter program, built once per program (dimension)."""
    if id(program) not in _tape_evaluators:
        _tape_evaluators[id(program)] = (program, numba_evaluator(program))
    return _tape_evaluators[id(program)][1]


def random_rotation(rng: np.random.Generator, dim: int, reflect: bool = False) -> np.ndarray:
    """A random rotation, or with ``reflect`` a random orthogonal matrix (reflections included).

    Rotations catch a transposed matrix even in 2D, where every reflection is symmetric.
    """
    q, r = np.linalg.qr(rng.normal(size=(dim, dim)))
    q = q * np.sign(np.diag(r))
    if not reflect and np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


def random_polytope_normals(rng, dim, extra):
    """Unit box normals (so the polytope is bounded) and ``extra`` random rows."""
    return np.vstack([np.eye(dim), -np.eye(dim), rng.normal(size=(extra, dim))])


# ---------------------------------------------------------------------- random instances
def make(kind: str, dim: int, rng: np.random.Generator, index: int) -> Oracle:
    """A random valid shape of ``kind``; ``index`` varies the counts (faces, vertices, holes)."""
    c = rng.uniform(-2, 2, dim)
    if kind == "ball":
        return nd.Ball(c, rng.uniform(0.5, 2))
    if kind == "box":
        return nd.Box(c, c + rng.uniform(0.5, 3, dim))
    if kind == "rounded_box":
        sides = rng.uniform(0.5, 3, dim)
        return nd.RoundedBox(c, c + sides, rng.uniform(0.05, 0.45) * sides.min())
    if kind == "half_space":
        return nd.HalfSpace(rng.normal(size=dim), rng.uniform(-1, 1))
    if kind == "slab":
        low = rng.uniform(-1, 0)
        return nd.Slab(rng.normal(size=dim), low, low + rng.uniform(0.3, 2))
    if kind == "capsule":
        b = c if index == 2 else c + rng.uniform(-2, 2, dim)  # the last one degenerate (a ball)
        return nd.Capsule(c, b, rng.uniform(0.3, 1))
    if kind == "cylinder":
        return nd.Cylinder(c, c + rng.uniform(-2, 2, dim), rng.uniform(0.3, 1))
    if kind == "polytope":
        normals = random_polytope_normals(rng, dim, extra=index + 1)
        offsets = np.concatenate([np.full(2 * dim, 2.0), rng.uniform(0.5, 1.5, index + 1)])
        return nd.ConvexPolytope(normals, offsets)
    if kind == "simplex":
        return nd.Simplex(c + rng.normal(size=(dim + 1, dim)))
    if kind == "ellipsoid":
        return nd.Ellipsoid(c, rng.uniform(0.3, 2, dim))
    if kind == "torus":
        major = rng.uniform(1, 2)
        return nd.Torus(c, major, rng.uniform(0.2, 0.8) * major)
    if kind == "polygon":
        return random_polygon(rng, n_vertices=5 + 4 * index, n_holes=index)
    raise ValueError(kind)


def random_polygon(rng, n_vertices, n_holes):
    """A star-shaped polygon around the origin (radii 2 to 3) with small holes near the middle.

    Its edges stay more than 1.3 from the origin when there are at least 8 vertices (jittered
    angles at most 72 degrees apart), so the holes (within 1.3 of it) are inside.
    """
    assert n_holes == 0 or n_vertices >= 8
    angles = 2 * np.pi * (np.arange(n_vertices) + rng.uniform(-0.3, 0.3, n_vertices)) / n_vertices
    radii = rng.uniform(2, 3, n_vertices)
    outer = np.column_stack([radii * np.cos(angles), radii * np.sin(angles)])
    holes = []
    for k in range(n_holes):
        centre = np.array([-0.8 + 1.6 * k, 0.0])
        corners = 3 + k
        turn = 2 * np.pi * np.arange(corners) / corners + rng.uniform(0, 1)
        holes.append(centre + 0.5 * np.column_stack([np.cos(turn), np.sin(turn)]))
    if rng.random() < 0.5:  # either orientation is accepted
        outer = outer[::-1]
    return nd.Polygon(outer, holes)


class Select(Oracle):
    """Test-only node: the shape ``shapes[which]``, with ``which`` read from the parameters.

    Many shapes thus share one compiled program (Numba compiles each function of a program,
    about 0.13 s apiece); the tests set ``which`` in the parameter array (its first entry) and
    compare with that shape's own oracle.
    """

    def __init__(self, shapes):
        self.shapes = list(shapes)
        self.dim = shapes[0].dim
        self._bounds = shapes[0].bounds

    def _kernel(self, program):
        offset = program.add_params([0.0])
        assert offset == 0
        lines = ["def _(p, prm):", "    which = int(prm[0])"]
        for i, shape in enumerate(self.shapes):
            lines += [f"    if which == {i}:", f"        return {program.shape(shape)}(p, prm)"]
        lines.append("    return 0.0")
        return program.define("\n".join(lines) + "\n")


#: Kinds in every dimension; the polytope last, as its face count (a parameter) changes the
#: offsets of the shapes after it, and with them the program text.
ND_KINDS = ["ball", "box", "rounded_box", "half_space", "slab", "capsule", "cylinder", "simplex",
            "ellipsoid", "polytope"]


def compare_all(shapes, rng, rounds):
    """Compare every shape of ``shapes(round)`` (a dict: label -> shape) through one selector program.

    The rounds have other numbers but the same structure: one program text (the same key), so
    Numba compiles it once.
    """
    keys = set()
    for round_ in range(rounds):
        labelled = shapes(round_)
        program = build(Select(list(labelled.values())))
        keys.add(program.key)
        prm = program.param_array()
        evaluate = numba_evaluator(program)
        for which, (label, shape) in enumerate(labelled.items()):
            prm[0] = which
            compare(shape, rng, program, prm, evaluate, label=f"{label} (round {round_}):")
    assert len(keys) == 1


@pytest.mark.parametrize("dim", DIMS)
def test_primitive_kernels_match_numpy(dim):
    rng = np.random.default_rng([dim, 1])
    compare_all(lambda round_: {kind: make(kind, dim, rng, round_) for kind in ND_KINDS}, rng, rounds=3)


def test_torus_and_polygon_kernels_match_numpy():
    rng = np.random.default_rng(7)
    # Directly, one program per shape (other numbers and vertex / hole counts: the same program).
    for kind, dim in [("torus", 3), ("polygon", 2)]:
        programs = [compare(make(kind, dim, rng, index), rng) for index in range(3)]
        assert len({program.key for program in programs}) == 1


def test_each_kind_built_alone_has_one_key_per_structure():
    rng = np.random.default_rng(3)
    for kind in ND_KINDS:
        keys = {build(make(kind, 4, rng, index)).key for index in range(3)}
        assert len(keys) == 1, kind
    keys = {build(make(kind, 4, rng, 0)).key for kind in ND_KINDS}
    assert len(keys) == len(ND_KINDS) - 1  # a simplex is a polytope


def test_simplex_uses_the_polytope_kernel():
    simplex = nd.Simplex([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    polytope = nd.ConvexPolytope(simplex.normals, simplex.offsets)
    assert build(simplex).key == build(polytope).key


# ---------------------------------------------------------------------- CSG nodes
def csg_nodes(dim: int, rng: np.random.Generator) -> dict[str, Oracle]:
    """Every CSG node on random children, keyed by a label for messages."""
    a = nd.Ball(rng.uniform(-0.5, 0.5, dim), rng.uniform(0.8, 1.5))
    b = nd.Box(rng.uniform(-1.5, -0.5, dim), rng.uniform(0.5, 1.5, dim))
    c = nd.Ellipsoid(rng.uniform(-1, 1, dim), rng.uniform(0.3, 1.0, dim))
    return {
        "union": nd.Union(a, b, c),
        "intersection": nd.Intersection(a, b),
        "complement": nd.Complement(a),
        "difference": nd.Difference(b, a),
        "translate": nd.Translate(b, rng.uniform(-2, 2, dim)),
        "rotate": nd.Rotate(b, random_rotation(rng, dim), rng.uniform(-1, 1, dim)),
        "scale": nd.Scale(b, rng.uniform(0.3, 3), rng.uniform(-1, 1, dim)),
        "dilate": nd.Offset(c, rng.uniform(0.1, 0.5)),
        "erode": nd.Offset(b, -rng.uniform(0.1, 0.4)),
        "shell": nd.Shell(a, rng.uniform(0.1, 0.5)),
        "smooth_union": nd.SmoothUnion(a, c.translate(np.full(dim, 0.8)), rng.uniform(0.2, 1.0)),
    }


@pytest.mark.parametrize("dim", DIMS)
def test_csg_kernels_match_numpy(dim):
    rng = np.random.default_rng([dim, 1000])
    compare_all(lambda round_: csg_nodes(dim, rng), rng, rounds=2)


def nested(dim: int, rng: np.random.Generator) -> Oracle:
    """A rotated, scaled difference of a union and an offset shell, smoothly merged and cut."""
    ball = nd.Ball(rng.uniform(-0.2, 0.2, dim), rng.uniform(1.0, 1.3))
    box = nd.Box(rng.uniform(-0.8, -0.5, dim), rng.uniform(0.7, 1.0, dim))
    ring = nd.Ellipsoid(np.zeros(dim), rng.uniform(0.5, 1.0, dim)).offset(0.1).shell(0.15)
    body = (ball | box.translate(rng.uniform(0.5, 0.9, dim))) - ring
    rotation = random_rotation(rng, dim, reflect=True)
    shape = body.rotate(rotation, rng.uniform(-1, 1, dim)).scale_by(rng.uniform(1.2, 2))
    capsule = nd.Capsule(np.zeros(dim), rng.uniform(0.5, 1.5, dim), rng.uniform(0.2, 0.4))
    return shape.smooth_union(capsule, 0.4) & ~nd.Ball(np.full(dim, 1.5), 0.5)


@pytest.mark.parametrize("dim", [3, 5])
def test_nested_csg(dim):
    rng = np.random.default_rng([dim, 2000])
    program = compare(nested(dim, rng), rng)
    # The same structure with other numbers: the same program text (compiled once), same key.
    assert compare(nested(dim, rng), rng).key == program.key


def test_equal_structures_share_a_key():
    rng = np.random.default_rng(5)

    def tree(seed_shift):
        r = np.random.default_rng(seed_shift)
        a = nd.Ball(r.uniform(-1, 1, 3), r.uniform(0.5, 1))
        b = nd.ConvexPolytope(random_polytope_normals(r, 3, extra=1), np.full(7, 1.5))
        return (a - b.offset(0.1)).rotate(random_rotation(r, 3)).translate(r.uniform(-1, 1, 3))

    assert build(tree(1)).key == build(tree(2)).key
    # Polygons with other vertex and hole counts: the counts are parameters, not program text.
    keys = {build(random_polygon(rng, n, holes)).key for n, holes in [(5, 0), (9, 1), (12, 2)]}
    assert len(keys) == 1
    # A different structure is a different program.
    assert build(tree(1)).key != build(tree(1) | nd.Ball(np.zeros(3), 1.0)).key


# ---------------------------------------------------------------------- NumPy plug-ins
def test_numpy_function_has_no_kernel():
    disc = nd.Function(lambda p: np.linalg.norm(p, axis=1) - 1.0, dim=2, bounds=[[-1, -1], [1, 1]])
    with pytest.raises(KernelError):
        build(disc)
    with pytest.raises(KernelError):
        build(nd.Box([-2, -2], [2, 2]) - disc.translate([0.5, 0.0]))


# ---------------------------------------------------------------------- program assembly
def test_library_dependencies_are_found_by_call():
    program = build(nd.RoundedBox([0, 0], [2, 1], 0.2))
    names = list(program.kernels)
    # box is called by rounded_box, so it comes first; nothing else is pulled in.
    assert names[:2] == ["box", "rounded_box"]
    assert "rounded_box" not in build(nd.Box([0, 0], [2, 1])).kernels


def test_warp_counters_are_variables():
    # Warp refuses to change a name bound to a bare constant in a dynamic loop.
    text = build(make("polygon", 2, np.random.default_rng(0), 1)).source("warp")
    assert "crossings = int(0)" in text
    assert "found = int(-1)" in text  # a negative constant too


def test_stack_holds_ints_in_every_dialect():
    from ndpack.kernels.language import Kernel

    source = (
        "def walk(p, prm):\n"
        "    s = stack()\n"
        "    s[0] = 3\n"
        "    s[1] = s[0] + 1\n"
        "    return float(s[1])\n"
    )
    kernel = Kernel(source)
    assert kernel.types["s"] == "stack"
    assert "np.empty(64, np.int64)" in kernel.render("numba", 2)
    assert "cuda.local.array(64, int32)" in kernel.render("cuda", 2)
    assert "Stack()" in kernel.render("warp", 2, "float32")
    with pytest.raises(KernelError, match="stack holds ints"):
        Kernel(source.replace("s[0] = 3", "s[0] = 3.5"))
    with pytest.raises(KernelError, match="cannot be both an array"):
        Kernel(source.replace("    s[0] = 3\n", "    s = 2.0\n"))


def test_use_binds_a_function_under_another_name():
    from ndpack.kernels.program import Program
    from ndpack.meshes import kernels

    for dim, element in ((2, "segment_query"), (3, "triangle_query")):
        program = Program(dim)
        kernels.add_queries(program)
        text = program.source("numba")
        assert "def element_query(" in text and f"def {element}(" not in text


_GRADIENT_LOOP = '''
def gradient_all(points, prm, hint, bound, out_feature, out_distance, out_gradient):
    for i in range(points.shape[0]):
        f = sd_feature(points[i], prm, hint[i], bound[i])
        out_feature[i] = f
        if f == -2.0:  # none within the bound
            continue
        out_distance[i] = sd_at(points[i], prm, f)
        for k in range(D):
            out_gradient[i, k] = sd_slope(points[i], prm, f, out_distance[i], k)
'''


def _compiled_gradient(shape, points, hint=None, bound=None):
    """The module's gradient entries (sd_feature, sd_at, sd_slope) run by Numba at ``points``,
    the search given ``hint`` and ``bound`` (k,) (default: none, -1 and 1e30)."""
    import numba

    from ndpack.kernels.compiled import compiled_program
    from ndpack.kernels.compile import numba_namespace

    def jit(namespace, names):
        for name in names:
            namespace[name] = numba.njit(namespace[name])

    flat = compiled_program(shape)
    params = flat.params
    namespace = numba_namespace(flat.program, "cpu", _GRADIENT_LOOP, jit)
    count = len(points)
    feature, distance, gradient = np.empty(count), np.empty(count), np.empty((count, shape.dim))
    hint = np.full(count, -1.0) if hint is None else np.asarray(hint, dtype=np.float64)
    bound = np.full(count, 1e30) if bound is None else np.asarray(bound, dtype=np.float64)
    namespace["gradient_all"](np.ascontiguousarray(points, dtype=np.float64), params, hint, bound, feature, distance,
                              gradient)
    return feature, distance, gradient


def test_mesh_and_outline_gradients_come_from_the_nearest_element():
    """A mesh's and an outline's compiled gradient (one tree walk) equals the NumPy oracle's
    nearest-point gradient, and the distance given the feature equals ``sd``; other shapes say
    they have none (feature -1) and keep central differences."""
    import trimesh

    rng = np.random.default_rng(3)
    mesh = nd.TriangleMesh.from_trimesh(trimesh.creation.icosphere(subdivisions=2))
    outline = nd.Polygon([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 0.4], [0.0, 1.0]])
    for shape in (mesh, outline):
        lower, upper = shape.bounds
        points = lower + (upper - lower) * rng.random((500, shape.dim))
        feature, distance, gradient = _compiled_gradient(shape, points)
        expected_distance, expected_gradient = shape.distance_and_gradient(points)
        assert np.all(feature >= 0)
        np.testing.assert_array_equal(distance, numba_evaluator(build(shape))(points, build(shape).param_array()))
        np.testing.assert_allclose(distance, expected_distance, rtol=0, atol=1e-12)
        np.testing.assert_allclose(gradient, expected_gradient, rtol=0, atol=1e-9)
    box = nd.Box(np.zeros(3), np.ones(3))
    points = rng.random((10, 3))
    feature, distance, gradient = _compiled_gradient(box, points)
    assert np.all(feature == -1) and np.all(gradient == 0)
    np.testing.assert_allclose(distance, box.distance(points), rtol=0, atol=1e-12)


def test_the_nearest_feature_search_given_a_hint_or_a_bound_finds_the_same_feature():
    """The search's pruning changes nothing it finds: from any hint the nearest feature is the
    unhinted one; with a bound, a closed surface reports -2 exactly where the boundary lies
    farther than the bound, and the same feature elsewhere. A mesh signed by winding numbers
    (here an open one, closed by its cap) ignores the bound."""
    import trimesh

    rng = np.random.default_rng(5)
    closed = nd.TriangleMesh.from_trimesh(trimesh.creation.icosphere(subdivisions=2))
    outline = nd.Polygon([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 0.4], [0.0, 1.0]])
    sphere = trimesh.creation.icosphere(subdivisions=2)
    open_mesh = nd.TriangleMesh(sphere.vertices, sphere.faces[1:], holes="cap")  # capped: winding numbers
    for shape in (closed, outline, open_mesh):
        lower, upper = shape.bounds
        points = lower + (upper - lower) * rng.random((400, shape.dim))
        unhinted = _compiled_gradient(shape, points)[0]
        elements = int(unhinted.max()) + 1
        hinted = _compiled_gradient(shape, points, hint=rng.integers(0, elements, len(points)))[0]
        np.testing.assert_array_equal(hinted, unhinted)
        unsigned = np.abs(shape.distance(points))
        bound = unsigned * rng.choice([0.5, 0.999, 1.001, 2.0], len(points))
        bounded = _compiled_gradient(shape, points, bound=bound)[0]
        if shape is open_mesh:
            np.testing.assert_array_equal(bounded, unhinted)
            continue
        farther = unsigned > bound
        assert 0 < farther.sum() < len(points)
        assert np.all(bounded[farther] == -2)
        np.testing.assert_array_equal(bounded[~farther], unhinted[~farther])


# ---------------------------------------------------------------------- language rules
def test_source_text_lines_count_blank_lines_and_comments():
    from ndpack.kernels.language import Kernel

    source = "def f(p, prm):\n\n    # a comment\n    x = p[0]\n\n    return sum(p) - x\n"
    with pytest.raises(KernelError, match=r"^kernel 'f', line 6: unknown function 'sum'"):
        Kernel(source)


def test_operators_print_with_pythons_meaning():
    """``//`` and ``%`` call Python-rounding helpers on Warp (numba already rounds as Python),
    ``**`` is float ** float everywhere; the Warp program defines the helpers it calls, only those."""
    from ndpack.kernels.language import Kernel
    from ndpack.kernels.program import Program

    kernel = Kernel(
        "def f(p, prm):\n"
        "    n = int(p[0])\n"
        "    m = n % 3 + n // 2\n"
        "    m %= 4\n"
        "    x = p[1] % 2.5 + p[1] // 0.5\n"
        "    k = n ** 2\n"
        "    k **= 2\n"
        "    return k + x + float(m) + 2 ** -1\n"
    )
    assert kernel.types["k"] == "float" and kernel.types["m"] == "int"  # ** gives floats
    numba = kernel.render("numba", 2)
    assert "n % 3 + n // 2" in numba and "m = m % 4" in numba and "float(n) ** float(2)" in numba
    assert "k = k ** float(2)" in numba and "float(2) ** float(-1)" in numba
    warp = kernel.render("warp", 2)
    assert "nd_mod_i(n, 3) + nd_floordiv_i(n, 2)" in warp and "m = nd_mod_i(m, 4)" in warp
    assert "nd_mod_f(p[1], wp.float64(2.5)) + nd_floordiv_f(p[1], wp.float64(0.5))" in warp
    assert "k = wp.pow(k, wp.float64(2))" in warp and " % " not in warp and "//" not in warp
    program = Program(2)
    program.kernels["f"] = kernel
    text = program.source("warp", "float32")
    assert text.count("def nd_") == 4 and "def nd_mod_f(a: wp.float32, b: wp.float32)" in text
    program.kernels["f"] = Kernel("def f(p, prm):\n    return float(int(p[0]) % 2)\n")
    assert program.source("warp").count("def nd_") == 1
    assert "def nd_" not in build(nd.Ball([0, 0], 1.0)).source("warp")


def test_paths_without_return_and_constant_indices_are_refused():
    from ndpack.kernels import library
    from ndpack.kernels.language import Kernel

    with pytest.raises(KernelError, match="line 3: a path through the function ends here without return"):
        Kernel("def f(p, prm):\n    x = p[0]\n    if x > 0.0:\n        return x\n")
    Kernel("def f(p, prm):\n    if p[0] > 0.0:\n        return 1.0\n    else:\n        return 2.0\n")
    with pytest.raises(KernelError, match="ends here without return"):
        Kernel("def f(p, prm):\n    while True:\n        if p[0] > 0.0:\n            break\n        return 1.0\n")
    # Library kernels are checked when printed for a dimension: the torus reads p[2].
    torus = Kernel(library.torus)
    assert "p[2]" in torus.render("numba", 3)
    with pytest.raises(KernelError, match=r"kernel 'torus', line \d+ of .*library.py: index 2 is out of range"):
        torus.render("numba", 2)
    with pytest.raises(KernelError, match="negative index -1"):
        Kernel("def f(p, prm):\n    return p[-1]\n").render("warp", 3)


def test_one_kernel_added_twice_is_one_and_another_of_its_name_is_numbered():
    from ndpack.kernels.language import Kernel
    from ndpack.kernels.program import Program

    program = Program(2)
    first = Kernel("def user_f(p, prm, o: int):\n    return p[0] - prm[o]\n")
    same = Kernel("def user_f(p, prm, o: int):\n    return p[0] - prm[o]\n")
    other = Kernel("def user_f(p, prm, o: int):\n    return p[1] - prm[o]\n")
    assert [program.add_kernel(k) for k in (first, same, other, first, other)] == [
        "user_f", "user_f", "user_f_2", "user_f", "user_f_2"]
    text = program.source("numba")
    assert "def user_f(" in text and "def user_f_2(p, prm, o):\n    return p[1] - prm[o]" in text
    assert other.name == "user_f"  # the kernel added keeps its name; the program holds a renamed copy
