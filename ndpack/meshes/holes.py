"""Closing the holes of an open triangle mesh with caps, so that its distance respects them.

A mesh's boundary is where its triangles' edges do not pair up: an edge ``a -> b`` used more often
than ``b -> a``. Each connected piece of that boundary (a hole's rim) is closed by a fan of
triangles ``(b, a, centre)`` to the rim's centre. The fan's edges pair up with the rim's, so the
capped mesh is a closed surface (a cycle: every edge used as often in each direction), whatever
the rim's shape: holes, non-manifold edges, rims that touch themselves.

Why a fan to the centre and not trimesh's ``fill_holes``: that fills only triangles and quads
unless asked for fans (then from a rim vertex), and finds rims with ``networkx.cycle_basis``,
which splits rims that touch themselves. A fan folds over itself where the rim is not convex or
not planar, but the winding number of a closed surface counts folded triangles with opposite
signs, so inside stays well defined; the distance to the folded triangles is then a lower bound
(they cover more than a flat cap would), which keeps spheres inside.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components


@dataclass
class Caps:
    """The caps of a mesh's holes.

    Attributes
    ----------
    centres : (k, 3) float64
        One new vertex per rim, appended after the mesh's vertices.
    faces : (c, 3) int64
        Cap triangles, indexing the mesh's vertices followed by ``centres``.
    sizes : (k,) float64
        Each rim's size: the diagonal of its bounding box.
    """

    centers: np.ndarray
    faces: np.ndarray
    sizes: np.ndarray

    @property
    def count(self) -> int:
        """Number of holes (rims)."""
        return len(self.centers)


#: The caps of a closed mesh.
NONE = Caps(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), np.zeros(0))


def boundary_edges(faces: np.ndarray) -> np.ndarray:
    """Directed edges of ``faces`` left without a partner in the opposite direction.

    Parameters
    ----------
    faces : (f, 3) int64

    Returns
    -------
    (b, 2) int64
        Edges ``(a, b)``, each repeated as often as ``a -> b`` outnumbers ``b -> a``; empty for a
        closed surface.
    """
    directed = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    forward = directed[:, 0] < directed[:, 1]
    undirected = np.sort(directed, axis=1)
    edges, inverse = np.unique(undirected, axis=0, return_inverse=True)
    balance = np.zeros(len(edges), dtype=np.int64)  # uses as (low, high) minus uses as (high, low)
    np.add.at(balance, inverse.ravel(), np.where(forward, 1, -1))
    unpaired = np.flatnonzero(balance)
    oriented = np.where((balance[unpaired] > 0)[:, None], edges[unpaired], edges[unpaired][:, ::-1])
    return np.repeat(oriented, np.abs(balance[unpaired]), axis=0)


def cap(vertices: np.ndarray, faces: np.ndarray) -> Caps:
    """Caps that close every hole of a mesh (none for a closed one).

    Parameters
    ----------
    vertices : (v, 3) float64
    faces : (f, 3) int64

    Returns
    -------
    Caps
        Rims are the connected pieces of :func:`boundary_edges`; each gets a vertex at its centre
        (the mean of its edges' midpoints, weighted by length, so uneven spacing does not pull it).
    """
    rim = boundary_edges(faces)
    if len(rim) == 0:
        return NONE
    graph = coo_matrix((np.ones(len(rim)), (rim[:, 0], rim[:, 1])), shape=(len(vertices),) * 2)
    _, labels = connected_components(graph, directed=False)
    pieces, piece = np.unique(labels[rim[:, 0]], return_inverse=True)
    ends = vertices[rim]  # (b, 2, 3)
    length = np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)
    weight = np.bincount(piece, length, minlength=len(pieces))
    centers = np.stack([np.bincount(piece, length * ends[:, :, i].mean(axis=1), minlength=len(pieces))
                        for i in range(3)], axis=1) / weight[:, None]
    lower = np.full((len(pieces), 3), np.inf)
    upper = np.full((len(pieces), 3), -np.inf)
    np.minimum.at(lower, piece, ends[:, 0])
    np.maximum.at(upper, piece, ends[:, 0])
    # The rim a -> b lacks its partner b -> a: the cap triangle (b, a, centre) supplies it.
    cap_faces = np.column_stack([rim[:, 1], rim[:, 0], len(vertices) + piece]).astype(np.int64)
    return Caps(centers, cap_faces, np.linalg.norm(upper - lower, axis=1))
