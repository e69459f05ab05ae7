"""An empty part of a CSG tree is a valid empty set; only an empty whole shape is refused."""

import manifold3d
import numpy as np
import pytest

import ndpack as nd
from ndpack.shapes.adapters import as_oracle
from ndpack.shapes.empty import Empty, Everything

BALL = nd.Ball([0.0, 0.0], 1.0)
EMPTY = BALL & nd.Ball([5.0, 5.0], 1.0)  # bounding boxes apart


def _same_packing(shape, reference, n=12):
    packing = nd.pack(shape, n, backend="numpy")
    expected = nd.pack(reference, n, backend="numpy")
    assert packing.verify().ok and len(packing) == n
    np.testing.assert_array_equal(packing.radii, expected.radii)
    np.testing.assert_array_equal(packing.centers, expected.centers)


def test_operators_leave_an_empty_part_out():
    assert isinstance(EMPTY, Empty) and "do not overlap" in EMPTY.reason
    assert BALL - EMPTY is BALL and BALL | EMPTY is BALL and EMPTY | BALL is BALL
    assert isinstance(BALL & EMPTY, Empty) and isinstance(EMPTY - BALL, Empty)
    assert isinstance(EMPTY | EMPTY, Empty)
    assert isinstance(~EMPTY, Everything) and isinstance(~~EMPTY, Empty)
    assert BALL & ~EMPTY is BALL and isinstance(BALL | ~EMPTY, Everything)
    assert isinstance(BALL - ~EMPTY, Empty)
    assert isinstance(~EMPTY - BALL, nd.Complement) and (~EMPTY - BALL).child is BALL
    assert BALL.smooth_union(EMPTY, 0.1) is BALL
    for moved in (EMPTY.translate([1, 2]), EMPTY.rotate(np.eye(2)), EMPTY.scale_by(2.0), EMPTY.offset(0.5),
                  EMPTY.shell(0.1), (~EMPTY).shell(0.1)):
        assert isinstance(moved, Empty)
    assert np.all(EMPTY.distance([[0.0, 0.0], [9.0, 9.0]]) == np.inf)
    assert EMPTY.volume().value == 0.0


def test_dimensions_are_still_checked():
    with pytest.raises(nd.DimensionError, match="different dimensions"):
        EMPTY | nd.Ball([0, 0, 0], 1)
    with pytest.raises(nd.DimensionError, match="different dimensions"):
        nd.Ball([0, 0, 0], 1) - EMPTY


def test_an_empty_whole_shape_is_refused_with_its_reason():
    with pytest.raises(nd.ShapeError, match="nothing to pack: the intersection .* do not overlap"):
        nd.pack(EMPTY, 5)
    with pytest.raises(nd.ShapeError, match="nothing to pack: .* less all of space"):
        nd.pack(BALL - ~EMPTY, 5)
    with pytest.raises(nd.BoundsError, match="unbounded"):
        nd.pack(~EMPTY, 5)


def test_nodes_built_by_their_classes_leave_an_empty_part_out_as_the_operators_do():
    apart = nd.Ball([5.0, 5.0], 1.0)
    everything = ~EMPTY
    pairs = [  # (class form, operator form)
        (nd.Union(BALL, EMPTY), BALL | EMPTY), (nd.Union(EMPTY, BALL, EMPTY), EMPTY | BALL | EMPTY),
        (nd.Union(EMPTY, EMPTY), EMPTY | EMPTY), (nd.Union(BALL, everything), BALL | everything),
        (nd.Intersection(BALL, EMPTY), BALL & EMPTY), (nd.Intersection(BALL, everything), BALL & everything),
        (nd.Intersection(BALL, apart), BALL & apart),
        (nd.Difference(BALL, EMPTY), BALL - EMPTY), (nd.Difference(EMPTY, BALL), EMPTY - BALL),
        (nd.Difference(BALL, everything), BALL - everything), (nd.Difference(everything, BALL), everything - BALL),
        (nd.Complement(EMPTY), ~EMPTY), (nd.Complement(everything), ~everything),
        (nd.Translate(EMPTY, [1.0, 0.0]), EMPTY.translate([1.0, 0.0])),
        (nd.Rotate(EMPTY, np.eye(2), center=[1.0, 0.0]), EMPTY.rotate(np.eye(2))),
        (nd.Scale(EMPTY, 2.0), EMPTY.scale_by(2.0)), (nd.Offset(EMPTY, 0.5), EMPTY.offset(0.5)),
        (nd.Shell(EMPTY, 0.1), EMPTY.shell(0.1)), (nd.Shell(everything, 0.1), everything.shell(0.1)),
        (nd.SmoothUnion(BALL, EMPTY, 0.1), BALL.smooth_union(EMPTY, 0.1)),
        (nd.SmoothUnion(EMPTY, BALL, 0.1), EMPTY.smooth_union(BALL, 0.1)),
    ]
    for built, operated in pairs:
        assert type(built) is type(operated) and repr(built) == repr(operated), (built, operated)
    assert nd.Union(BALL, EMPTY) is BALL and nd.Difference(BALL, EMPTY) is BALL
    # Deeper in a tree, and packed: the same shape, the same packing.
    shifted = nd.Ball([0.5, 0.0], 0.6)
    built = nd.Difference(nd.Union(BALL, nd.Intersection(shifted, apart)), nd.Translate(EMPTY, [0.3, 0.0]))
    assert built is BALL
    built = nd.Intersection(nd.Union(BALL, EMPTY), nd.Difference(shifted, nd.Scale(EMPTY, 2.0)), nd.Complement(EMPTY))
    assert isinstance(built, nd.Intersection) and repr(built) == repr(BALL & shifted)
    _same_packing(built, (BALL | EMPTY) & (shifted - EMPTY.scale_by(2.0)) & ~EMPTY)
    # Nodes without an empty part, and the classes' own errors, as before.
    assert isinstance(nd.Union(BALL, shifted), nd.Union) and isinstance(nd.Difference(BALL, shifted), nd.Difference)
    with pytest.raises(nd.ShapeError, match="Union needs at least two shapes, got 1"):
        nd.Union(EMPTY)
    with pytest.raises(nd.DimensionError, match="different dimensions"):
        nd.Union(EMPTY, nd.Ball([0, 0, 0], 1))


def test_an_intersection_empty_as_a_whole_is_refused_where_it_is_packed():
    for empty in (nd.Intersection(BALL, nd.Ball([5.0, 5.0], 1.0)), nd.Intersection(BALL, EMPTY),
                  nd.Difference(BALL, ~EMPTY), nd.Union(EMPTY, EMPTY)):
        assert isinstance(empty, Empty)
        with pytest.raises(nd.ShapeError, match="^there is nothing to pack: "):
            nd.pack(empty, 5)
    with pytest.raises(nd.ShapeError, match="nothing to pack: the intersection of Ball.* do not overlap"):
        nd.pack(nd.Intersection(BALL, nd.Ball([5.0, 5.0], 1.0)), 5)
    # Boxes that overlap, balls that do not: no interior point, said so (and no sphere).
    with pytest.raises(nd.ShapeError, match="found no interior point of Intersection"):
        nd.pack(nd.Intersection(BALL, nd.Ball([1.9, 1.9], 1.0)), 5)


def test_fuzzing_regression_an_empty_cross_section_subtracted():
    """Found by the fuzzing run of the trust issue: refused as "the manifold3d cross-section is
    empty", though subtracting nothing leaves the ellipse."""
    section = (manifold3d.CrossSection.square([0.4718, 0.3278], True).translate([-0.2298, 0.3558])
               ^ manifold3d.CrossSection.circle(0.3842, 44).rotate(-154.597).translate([0.0861, -0.2377]))
    section = section - manifold3d.CrossSection.square([0.8916, 0.5085], True).translate([0.3275, -0.2511])
    assert section.is_empty()
    ellipse = nd.Ellipsoid([-0.079, 0.3642], [0.365, 0.6576])
    shape = ellipse - section
    assert shape is ellipse
    _same_packing(shape, ellipse)


def test_fuzzing_regression_empty_branches_of_a_union():
    """An empty manifold3d solid and an intersection of parts apart, each a branch of a union
    whose other branch is not empty: the union is that branch."""
    cube = nd.Box([0.0, 0.0, 0.0], [1.0, 1.0, 1.0])
    hollowed = manifold3d.Manifold.cube([1.0, 1.0, 1.0]) - manifold3d.Manifold.cube([2.0, 2.0, 2.0]).translate(
        [-0.5, -0.5, -0.5])
    apart = nd.Ball([3.0, 3.0, 3.0], 0.5) & nd.Ball([-3.0, -3.0, -3.0], 0.5)
    shape = (cube | hollowed) | apart.translate([0.1, 0.0, 0.0])
    assert shape is cube
    _same_packing(shape, cube, n=8)
    # Written with the classes (the manifold3d part converted first: classes take ndpack shapes).
    apart = nd.Intersection(nd.Ball([3.0, 3.0, 3.0], 0.5), nd.Ball([-3.0, -3.0, -3.0], 0.5))
    assert nd.Union(nd.Union(cube, as_oracle(hollowed)), nd.Translate(apart, [0.1, 0.0, 0.0])) is cube
    # The same with the empty parts deeper in the tree.
    shape = (cube - apart) & (nd.Ball([0.5, 0.5, 0.5], 2.0) | hollowed)
    assert isinstance(shape, nd.Intersection)
    _same_packing(shape, cube & nd.Ball([0.5, 0.5, 0.5], 2.0), n=8)
