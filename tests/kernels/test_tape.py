"""Shapes as data: the tape a tree of built-ins becomes, and the interpreter that runs it.

Every shape's tape is compared with its NumPy oracle in test_kernels.py; here: what is shared
(one program per dimension, whatever the tree, its numbers or its meshes), how trees are laid
out (transforms composed into the leaves, nested unions flattened, constants scaled), and the
fallback to a specialised program for trees too deep for the tape's registers.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

import ndpack as nd
from ndpack.kernels.compiled import compiled_program
from ndpack.kernels import tape as tapes
from ndpack.kernels.compile import numba_evaluator
from ndpack.kernels.tape import flatten


def evaluate(shape, points):
    flat = flatten(shape)
    return numba_evaluator(flat.program)(points, flat.params)


def test_every_tree_of_a_dimension_shares_one_program():
    ball = nd.Ball([0.0, 0.0, 0.0], 1.0)
    trees = [
        ball,
        nd.Ball([1.0, 2.0, 3.0], 0.001),
        nd.Box([0, 0, 0], [2.7, 2.7, 2.7]) - ball,
        (nd.Box([0, 0, 0], [1, 1, 1]) | nd.Capsule([0, 0, 0], [1.5, 1.5, 0], 0.3))
        - nd.Cylinder([0, 0, -1], [0, 0, 1], 0.2),
        nd.Torus([0, 0, 0], 1.0, 0.3).rotate(nd.rotation(3, 0.4, (1, 2))).scale_by(3.0).offset(0.1).shell(0.05),
        ball.smooth_union(nd.Ellipsoid([1, 0, 0], [0.5, 0.3, 0.2]), 0.2) & ~nd.Slab([0, 0, 1], -0.1, 0.1),
    ]
    programs = {id(flatten(tree).program) for tree in trees}
    assert len(programs) == 1
    assert flatten(nd.Ball([0.0] * 4, 1.0)).program is not flatten(ball).program  # another dimension


def test_meshes_alone_share_a_program_without_the_interpreter():
    sphere = nd.TriangleMesh.from_trimesh(trimesh.creation.icosphere(subdivisions=1))
    capsule = nd.TriangleMesh.from_trimesh(trimesh.creation.capsule(height=1.0, radius=0.4))
    alone = flatten(sphere).program
    assert flatten(capsule).program is alone and alone.title == "meshes"
    # Only the surface queries: no interpreter, no primitives (a third less for numba-cuda to compile).
    assert "tape_primitive" not in alone.kernels and "box" not in alone.kernels and "surface_feature" in alone.kernels
    # A mesh alone (untransformed) gives its gradient to the backends: prm[1] is its block.
    assert flatten(sphere).params[1] == tapes.HEADER
    # In a tree, or moved, it is a leaf of the interpreter with surfaces, shared by such trees.
    with_box = capsule - nd.Box([0, 0, 0], [1, 1, 1])
    moved = sphere.translate([1, 0, 0])
    assert flatten(with_box).program is flatten(moved).program is not alone
    assert "meshes" in flatten(with_box).program.title and "tape_primitive" in flatten(with_box).program.kernels
    assert flatten(with_box).program is not flatten(nd.Ball([0.0] * 3, 1.0)).program
    assert flatten(with_box).params[1] == -1 and flatten(moved).params[1] == -1


def test_a_mesh_alone_gives_the_interpreters_distances():
    """The mesh's own program and the interpreter (the mesh as a leaf of a union with itself)
    give the same distances on numba, to the bit."""
    from ndpack.backends import get_backend

    mesh = nd.TriangleMesh.from_trimesh(trimesh.creation.capsule(height=1.0, radius=0.4))
    points = np.random.default_rng(3).uniform(-1.0, 1.0, (200, 3))
    backend = get_backend("numba")
    tree = mesh | mesh
    assert flatten(tree).program is not flatten(mesh).program
    np.testing.assert_array_equal(backend.distance(mesh, points), backend.distance(tree, points))


def test_plugins_key_the_program_by_their_code_not_their_numbers_or_tree():
    def bump(p, params):
        return math.sqrt(p[0] * p[0] + p[1] * p[1]) - params[0]

    def other(p, params):
        return abs(p[0]) + abs(p[1]) - params[0]

    bounds = [[-1.0, -1.0], [1.0, 1.0]]
    one = nd.ScalarFunction(bump, 2, bounds, params=[0.5])
    two = nd.ScalarFunction(bump, 2, bounds, params=[0.7])
    square = nd.Box([-1, -1], [1, 1])
    assert flatten(one).program is flatten(square - two.translate([0.2, 0.0])).program
    mixed = flatten(nd.ScalarFunction(other, 2, bounds, params=[0.5]) | one)
    assert mixed.program is flatten(one | nd.ScalarFunction(other, 2, bounds, params=[0.1])).program
    assert mixed.program is not flatten(one).program
    points = np.random.default_rng(0).uniform(-1, 1, (200, 2))
    shape = nd.ScalarFunction(other, 2, bounds, params=[0.5]) | one
    np.testing.assert_allclose(evaluate(shape, points), shape.distance(points), rtol=0, atol=1e-12)


def test_transforms_are_composed_into_the_leaves():
    ball = nd.Ball([0.2, 0.0, 0.0], 0.5)
    shape = ball.translate([1, 0, 0]).rotate(nd.rotation(3, 0.3), center=[0.5, 0.5, 0]).scale_by(2.0)
    tape = tapes.Tape(3)
    tape.add(shape)
    flat = tape.finish()
    assert len(tape.instructions) == 1  # one leaf: the three transforms are one block
    points = np.random.default_rng(1).uniform(-3, 3, (300, 3))
    np.testing.assert_allclose(evaluate(shape, points), shape.distance(points), rtol=0, atol=1e-12)
    # Constants under a scale are stored scaled: an offset of 0.1 in the child is 0.2 here.
    offset = nd.Offset(ball, 0.1).scale_by(2.0)
    np.testing.assert_allclose(evaluate(offset, points), offset.distance(points), rtol=0, atol=1e-12)
    assert 0.2 in flatten(offset).params
    assert flat.params[0] == 1


def test_nested_unions_flatten_so_chains_stay_shallow():
    balls = [nd.Ball([0.3 * k, 0.0], 0.2) for k in range(30)]
    right_deep = balls[-1]
    for ball in reversed(balls[:-1]):
        right_deep = nd.Union(ball, right_deep)  # a | (b | (c | ...))
    tape = tapes.Tape(2)
    tape.add(right_deep)
    assert tape.depth == 2
    difference_chain = nd.Box([-1, -1], [10, 1])
    for ball in balls:
        difference_chain = difference_chain - ball
    tape = tapes.Tape(2)
    tape.add(difference_chain)
    assert tape.depth == 2
    points = np.random.default_rng(2).uniform([-1, -1], [10, 1], (300, 2))
    for shape in (right_deep, difference_chain):
        np.testing.assert_allclose(evaluate(shape, points), shape.distance(points), rtol=0, atol=1e-12)


def test_a_tree_too_deep_for_the_tape_is_compiled_as_its_own_program():
    # a - (b - (c - ...)): each level keeps one more value waiting.
    shape = nd.Ball([0.0, 0.0], 0.1)
    for k in range(tapes.REGISTERS + 1):
        shape = nd.Ball([0.0, 0.0], 0.3 + 0.1 * k) - shape
    with pytest.raises(tapes.TapeTooDeep, match="needs 10 values"):
        flatten(shape)
    flat = compiled_program(shape)
    assert "specialised" in flat.program.title
    points = np.random.default_rng(3).uniform(-1.5, 1.5, (300, 2))
    np.testing.assert_allclose(numba_evaluator(flat.program)(points, flat.params), shape.distance(points),
                               rtol=0, atol=1e-12)
    # Two levels fewer fit: REGISTERS values at once.
    fits = nd.Ball([0.0, 0.0], 0.1)
    for k in range(tapes.REGISTERS - 1):
        fits = nd.Ball([0.0, 0.0], 0.3 + 0.1 * k) - fits
    tape = tapes.Tape(2)
    tape.add(fits)
    assert tape.depth == tapes.REGISTERS and "specialised" not in compiled_program(fits).program.title


def test_specialised_kernels_on_request(monkeypatch):
    shape = nd.Box([0, 0], [1, 1]) - nd.Ball([1, 1], 0.5)
    monkeypatch.setenv("NDPACK_KERNELS", "specialised")
    special = compiled_program(shape)
    assert "specialised" in special.program.title
    monkeypatch.setenv("NDPACK_KERNELS", "tape")
    assert compiled_program(shape).program is flatten(shape).program
    monkeypatch.setenv("NDPACK_KERNELS", "fastest")
    with pytest.raises(nd.BackendError, match="NDPACK_KERNELS must be one of tape, specialised"):
        compiled_program(shape)


def test_the_same_packing_from_the_tape_and_the_specialised_program(monkeypatch):
    # Untransformed, both compute the same arithmetic: the same packing. Transformed, the tape
    # composes the maps into one: rounding differs in the last bits, and convergence by central
    # differences carries that to about 1e-4 of a small sphere's radius.
    plain = nd.Box([0, 0], [1, 1]) - nd.Ball([1, 1], 0.5)
    moved = plain.rotate(nd.rotation(2, 0.3)).translate([0.2, 0.1]).scale_by(1.5)
    tape = [nd.pack(shape, 60, grid=24, backend="numba") for shape in (plain, moved)]
    monkeypatch.setenv("NDPACK_KERNELS", "specialised")
    special = [nd.pack(shape, 60, grid=24, backend="numba") for shape in (plain, moved)]
    assert all(packing.verify().ok for packing in tape + special)
    np.testing.assert_allclose(tape[0].radii, special[0].radii, rtol=0, atol=1e-12)
    np.testing.assert_allclose(tape[1].radii[:5], special[1].radii[:5], rtol=1e-5, atol=0)
    np.testing.assert_allclose(tape[1].radii, special[1].radii, rtol=1e-3, atol=0)
    assert abs(tape[1].fill / special[1].fill - 1) < 1e-4
