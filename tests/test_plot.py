"""Pictures: slices of spheres are the right circles, and a plot draws them all."""

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import ndpack as nd  # noqa: E402
from ndpack.plot import slice_circles  # noqa: E402


def test_slice_circles_in_4d():
    centers = np.array([[0, 0, 0.0, 0.0], [1, 1, 0.3, 0.4], [2, 2, 0.9, 0.0]])
    radii = np.array([1.0, 0.6, 0.5])
    c2, r2, index = slice_circles(centers, radii, axes=(0, 1), at=np.zeros(4))
    np.testing.assert_array_equal(index, [0, 1])  # the third sphere misses the plane
    np.testing.assert_allclose(r2, [1.0, np.sqrt(0.36 - 0.25)])
    np.testing.assert_array_equal(c2, [[0, 0], [1, 1]])
    with pytest.raises(nd.DimensionError):
        slice_circles(centers, radii, axes=(0, 0))


def test_plot_draws_every_circle_with_the_outline(tmp_path):
    packing = nd.pack(nd.Box([0, 0], [2, 1]) - nd.Ball([1, 0.5], 0.3), n=60, seed=0)
    ax = packing.plot()
    circles = ax.collections[0]
    assert len(circles.get_paths()) == 60
    np.testing.assert_allclose(circles.get_array(), packing.radii)
    assert len(ax.collections) >= 2  # the outline contour
    ax.figure.savefig(tmp_path / "p.png")
    assert (tmp_path / "p.png").stat().st_size > 1000
