"""Property-based checks: random CSG trees stay conservative and pack validly."""

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import ndpack as nd

coordinate = st.floats(-1.0, 1.0, allow_nan=False)


@st.composite
def primitives(draw, dim):
    center = np.array(draw(st.lists(coordinate, min_size=dim, max_size=dim)))
    size = draw(st.floats(0.3, 1.0))
    kind = draw(st.sampled_from(["ball", "box", "capsule"]))
    if kind == "ball":
        return nd.Ball(center, size)
    if kind == "box":
        return nd.Box(center - size, center + size * draw(st.floats(0.5, 1.5)))
    return nd.Capsule(center, center + size, size / 2)


@st.composite
def csg_trees(draw):
    dim = draw(st.sampled_from([2, 3, 4]))
    shape = draw(primitives(dim))
    for _ in range(draw(st.integers(1, 3))):
        other = draw(primitives(dim))
        operation = draw(st.sampled_from(["union", "difference", "offset", "rotate"]))
        if operation == "union":
            shape = shape | other
        elif operation == "difference":
            shape = shape - other.scale_by(0.5, center=other.bounds.mean(axis=0))
        elif operation == "offset":
            shape = shape.offset(draw(st.floats(-0.05, 0.1)))
        else:
            shape = shape.rotate(nd.rotation(dim, draw(st.floats(0, 6.3)), (0, dim - 1)))
    return shape


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(csg_trees(), st.integers(0, 2**16))
def test_random_csg_is_one_lipschitz(shape, seed):
    rng = np.random.default_rng(seed)
    lower, upper = shape.bounds
    points = lower + (upper - lower) * rng.random((400, shape.dim))
    others = points + rng.normal(scale=0.1, size=points.shape)
    ratio = np.abs(shape.distance(points) - shape.distance(others)) / np.linalg.norm(points - others, axis=1)
    assert ratio.max() <= 1 + 1e-9


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(csg_trees(), st.integers(0, 100))
def test_random_csg_packs_validly(shape, seed):
    try:
        packing = nd.pack(shape, n=12, grid=12, seed=seed)
    except nd.ShapeError as error:  # a difference may remove everything: that must be said
        assert "no interior point" in str(error) or "nothing to pack" in str(error)
        return
    report = nd.verify(packing, shape)
    assert report.ok, report.summary()
    assert len(packing) >= 1
