"""Pictures: slices of spheres are the right circles, a plot draws them all, and a mesh's slice its
cut outline."""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest

import ndpack as nd
from ndpack.pictures import slice_circles


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


def column(axis, count=5, **params):
    """Touching unit-diameter spheres in a row along ``axis`` (a tall box), no shape."""
    centers = np.zeros((count, 3))
    centers[:, axis] = np.arange(count)
    packing = nd.Packing(centers, np.full(count, 0.5), np.zeros(count, dtype=np.int64), 1.0)
    packing.params.update(params)
    return packing


def test_a_3d_slice_stands_the_up_axis_vertical(tmp_path):
    from ndpack.pictures import plot, save_figure

    for axis, horizontal in ((1, "x0"), (2, "x0"), (0, "x1")):
        ax = plot(column(axis))
        assert (ax.get_xlabel(), ax.get_ylabel()) == (horizontal, f"x{axis}")
        assert len(ax.collections[0].get_paths()) == 5  # the plane through the centres cuts every sphere
    # The mesh file's convention, an asked-for axis, one pointing down, and given axes.
    ax = plot(column(2, source="tower.obj"))
    assert ax.get_ylabel() == "x1"
    ax = plot(column(1), up="-z")
    assert ax.get_ylabel() == "x2" and ax.get_ylim()[0] > ax.get_ylim()[1]
    assert plot(column(1), axes=(0, 2)).get_ylabel() == "x2"
    assert plot(column(1), axes=(2, 0), up="z").get_ylabel() == "x2"  # reordered: up goes vertical
    with pytest.raises(nd.ParameterError, match="not one of the axes drawn"):
        plot(column(1), axes=(0, 1), up="z")
    with pytest.raises(nd.ParameterError, match=r"auto, x, y, z"):
        save_figure(column(1), tmp_path / "p.svg", up="up")
    # 2-D and beyond three dimensions keep (0, 1).
    assert nd.pack(nd.Box([0, 0], [2, 1]), n=5, seed=0).plot().get_ylabel() == "x1"


MESH = Path(__file__).resolve().parents[1] / "data" / "meshes" / "cow.ply"


def outline_points(ax):
    """(k, 2) points of the mesh section a slice draws (its LineCollection labelled "outline")."""
    from matplotlib.collections import LineCollection

    outlines = [c for c in ax.collections if isinstance(c, LineCollection) and c.get_label() == "outline"]
    assert len(outlines) == 1, [type(c).__name__ for c in ax.collections]
    return np.concatenate(outlines[0].get_segments())


def test_a_mesh_slice_draws_the_cut_outline(tmp_path):
    mesh = nd.TriangleMesh.load(MESH)
    packing = nd.pack(mesh, n=100, seed=0, mode="fast", grid=12)
    at = packing.centers.mean(axis=0)
    ax = packing.plot()
    horizontal, vertical = ax.get_xlabel(), ax.get_ylabel()
    axes = [int(horizontal[1:]), int(vertical[1:])]
    points = np.tile(at, (len(outline_points(ax)), 1))
    points[:, axes] = outline_points(ax)
    assert len(points) > 20  # a closed curve around the cow's body, not a few stray segments
    # Every point of the outline lies on the surface, in the plane through the centres' mean.
    size = np.ptp(mesh.bounds, axis=0).max()
    assert np.abs(mesh.distance(points)).max() < 1e-9 * size
    # Loaded from its file the packing has no shape; the mesh file it records draws the outline.
    loaded = nd.Packing.load(packing.save(tmp_path / "cow.npz"))
    assert loaded.shape is None
    loaded.params["source"] = str(MESH)  # as `ndpack pack` records it
    np.testing.assert_allclose(outline_points(loaded.plot()), outline_points(ax))
    loaded.params["source"] = str(tmp_path / "gone.ply")  # a file no longer there: circles alone
    assert len(loaded.plot().collections) == 1
