"""Triangle meshes and 2-D outlines as the flat parameter blocks their kernels read
(:mod:`ndpack.meshes.kernels`)."""

from __future__ import annotations

import functools

import numpy as np

from .. import compile_ahead as ahead
from . import bvh
from .kernels import HEADER, SEGMENT, TRIANGLE, WINDING, node_size

#: Sign methods, as stored in the header.
SIGN_CODES = {"pseudonormal": 0.0, "winding": 1.0, "even-odd": 2.0}
#: A tree node counts as one dipole in the winding number when the query point is farther than
#: this many node radii from its centre (Barill et al. use 2; the first-order error is then a few
#: hundredths, at most 0.08 measured on the rocker arm: far from the 0.5 threshold except next to holes).
FAR_FIELD_RATIO = 2.0


def pseudo_normals(vertices: np.ndarray, faces: np.ndarray):
    """Angle-weighted pseudo-normals (Baerentzen and Aanaes 2005) of an indexed mesh.

    Parameters
    ----------
    vertices : (v, 3) float64
    faces : (f, 3) int64, consistently oriented

    Returns
    -------
    face_normals : (f, 3) float64
        Unit normals.
    edge_normals : (f, 3, 3) float64
        Per face, the sum of the normals of the faces sharing its edges ab, bc, ca.
    vertex_normals : (f, 3, 3) float64
        Per face, the angle-weighted sum of normals around its vertices a, b, c.
    """
    corners = vertices[faces]  # (f, 3, 3)
    cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    face_normals = cross / np.linalg.norm(cross, axis=1, keepdims=True)

    # Interior angle at each corner.
    after = np.roll(corners, -1, axis=1) - corners
    before = np.roll(corners, 1, axis=1) - corners
    cosine = np.einsum("fki,fki->fk", after, before)
    cosine /= np.linalg.norm(after, axis=2) * np.linalg.norm(before, axis=2)
    angles = np.arccos(np.clip(cosine, -1.0, 1.0))
    around_vertex = np.zeros_like(vertices)
    np.add.at(around_vertex, faces.ravel(), (angles[:, :, None] * face_normals[:, None, :]).reshape(-1, 3))

    edges = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    _, edge_ids = np.unique(edges, axis=0, return_inverse=True)
    edge_ids = edge_ids.ravel()
    around_edge = np.zeros((edge_ids.max() + 1, 3))
    np.add.at(around_edge, edge_ids, np.repeat(face_normals, 3, axis=0))
    return face_normals, around_edge[edge_ids].reshape(-1, 3, 3), around_vertex[faces]


def pack_mesh(vertices: np.ndarray, faces: np.ndarray, sign: str) -> np.ndarray:
    """The parameter block of a mesh, with offsets counted from the block's start.

    Parameters
    ----------
    vertices : (v, 3) float64
    faces : (f, 3) int64
        A cleaned mesh (no degenerate faces), outward oriented where it is closed.
    sign : "pseudonormal" or "winding"

    Returns
    -------
    block : (k,) float64
        Header, nodes, triangles and winding data (layout in :mod:`ndpack.meshes.kernels`).
        :func:`relocate` shifts its offsets when it is placed elsewhere in a larger array.
    order : (f,) int64
        The row of ``faces`` of each triangle in the block (leaf order).
    """
    lower, upper = vertices.min(axis=0), vertices.max(axis=0)
    center = 0.5 * (lower + upper)
    scale = 0.5 * float((upper - lower).max())
    unit = (vertices - center) / scale
    triangles = unit[faces]
    tree = bvh.build(triangles)
    order = tree.order
    face_normals, edge_normals, vertex_normals = pseudo_normals(unit, faces)

    triangle_block = np.concatenate([
        triangles[order].reshape(-1, 9), face_normals[order],
        edge_normals[order].reshape(-1, 9), vertex_normals[order].reshape(-1, 9),
    ], axis=1)
    winding_block = _compiled_winding_data()(triangles[order], tree.lower, tree.upper, tree.first, tree.count)

    assert triangle_block.shape[1] == TRIANGLE and winding_block.shape[1] == WINDING
    block = _assemble(tree, center, scale, sign, triangle_block, winding_block)
    return block, order


def pack_outline(segments: np.ndarray, vertex_normals: np.ndarray) -> np.ndarray:
    """The parameter block of a closed 2-D outline, signed by the even-odd rule.

    Parameters
    ----------
    segments : (e, 2, 2) float64
        Edges as (start, end), every ring closed.
    vertex_normals : (e, 2, 2) float64
        Pseudo-normals at each edge's start and end (the sum of the two edges' normals).

    Returns
    -------
    (k,) float64
        Offsets counted from the block's start, like :func:`pack_mesh`.
    """
    points = segments.reshape(-1, 2)
    lower, upper = points.min(axis=0), points.max(axis=0)
    center = 0.5 * (lower + upper)
    scale = 0.5 * float((upper - lower).max())
    unit = (segments - center) / scale
    tree = bvh.build(unit)
    edge = unit[:, 1] - unit[:, 0]
    normal = np.column_stack([edge[:, 1], -edge[:, 0]]) / np.linalg.norm(edge, axis=1, keepdims=True)
    order = tree.order
    element_block = np.concatenate([unit[order].reshape(-1, 4), normal[order], vertex_normals[order].reshape(-1, 4)],
                                   axis=1)
    assert element_block.shape[1] == SEGMENT
    return _assemble(tree, np.append(center, 0.0), scale, "even-odd", element_block, np.zeros((0, WINDING)))


def _assemble(tree, center, scale, sign, element_block, winding_block) -> np.ndarray:
    """Header, nodes, elements and winding data as one block (offsets from its start)."""
    dim = tree.lower.shape[1]
    node_block = np.concatenate([tree.lower, tree.upper, tree.first[:, None], tree.count[:, None]], axis=1)
    nodes_at = HEADER
    elements_at = nodes_at + node_size(dim) * tree.n_nodes
    winding_at = elements_at + element_block.size
    header = np.array([tree.n_nodes, SIGN_CODES[sign], scale, *center, FAR_FIELD_RATIO**2,
                       nodes_at, elements_at, winding_at, element_block.shape[1], 0, 0, 0, 0])
    assert header.size == HEADER and node_block.shape[1] == node_size(dim)
    return np.concatenate([header, node_block.ravel(), element_block.ravel(), winding_block.ravel()])


def warp_mesh_id(block: np.ndarray, device) -> np.ndarray:
    """(4,) the id of a ``wp.Mesh`` of the block's triangles on ``device``, in 16-bit pieces.

    The mesh is kept with the block's owner (see :class:`ndpack.TriangleMesh`): its id is a
    pointer, valid only while the mesh lives.
    """
    import warp as wp

    elements_at, winding_at, stride = int(block[8]), int(block[9]), int(block[10])
    corners = block[elements_at:winding_at].reshape(-1, stride)[:, :9].reshape(-1, 3).astype(np.float32)
    mesh = wp.Mesh(points=wp.array(corners, dtype=wp.vec3, device=device),
                   indices=wp.array(np.arange(len(corners), dtype=np.int32), dtype=wp.int32, device=device))
    pieces = np.array([(mesh.id >> (16 * k)) & 0xFFFF for k in range(4)], dtype=np.float64)
    return pieces, mesh


def relocate(block: np.ndarray, offset: int) -> np.ndarray:
    """A copy of ``block`` whose internal offsets are absolute once placed at ``offset``."""
    block = block.copy()
    block[7:10] += offset
    return block


#: ``_winding_data``'s argument types as :func:`pack_mesh` passes them (Numba's words), and the job of
#: the compile helper that compiles it for them (:func:`ndpack.meshes.queries.compile_ahead`).
WINDING_SIGNATURE = "(float64[:, :, ::1], float64[:, ::1], float64[:, ::1], int64[::1], int64[::1])"
AHEAD_JOB = "numba: the mesh's winding data"


@functools.cache
def _compiled_winding_data():
    ahead.wait(AHEAD_JOB)
    import numba

    return numba.njit(cache=True)(_winding_data)


def _winding_data(triangles, lower, upper, first, count):
    """(m, 7): per node, area vector, area-weighted centroid and a radius enclosing its triangles.

    In scalar loops (the same operations, in the same order, as the array expressions they
    replaced): Numba compiles those several times slower, and a fresh machine's first mesh waits."""
    n_nodes = len(first)
    data = np.zeros((n_nodes, 7))
    area = np.zeros(n_nodes)
    for k in range(n_nodes - 1, -1, -1):  # children have larger indices than their parent
        if count[k] > 0:
            for j in range(first[k], first[k] + count[k]):
                u0 = triangles[j, 1, 0] - triangles[j, 0, 0]
                u1 = triangles[j, 1, 1] - triangles[j, 0, 1]
                u2 = triangles[j, 1, 2] - triangles[j, 0, 2]
                v0 = triangles[j, 2, 0] - triangles[j, 0, 0]
                v1 = triangles[j, 2, 1] - triangles[j, 0, 1]
                v2 = triangles[j, 2, 2] - triangles[j, 0, 2]
                w0 = 0.5 * (u1 * v2 - u2 * v1)  # half the cross product: the area vector
                w1 = 0.5 * (u2 * v0 - u0 * v2)
                w2 = 0.5 * (u0 * v1 - u1 * v0)
                size = np.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
                data[k, 0] += w0
                data[k, 1] += w1
                data[k, 2] += w2
                for i in range(3):
                    data[k, 3 + i] += size * (triangles[j, 0, i] + triangles[j, 1, i] + triangles[j, 2, i]) / 3.0
                area[k] += size
        else:
            for child in (k + 1, first[k]):
                for i in range(3):
                    data[k, i] += data[child, i]
                for i in range(3):
                    data[k, 3 + i] += area[child] * data[child, 3 + i]
                area[k] += area[child]
        for i in range(3):
            if area[k] > 0.0:
                data[k, 3 + i] /= area[k]
            else:
                data[k, 3 + i] = 0.5 * (lower[k, i] + upper[k, i])
        # The farthest box corner bounds the distance to every vertex in the node.
        radius = 0.0
        for corner in range(8):
            s = 0.0
            for i in range(3):
                x = upper[k, i] if (corner >> i) & 1 else lower[k, i]
                s += (x - data[k, 3 + i]) ** 2
            radius = max(radius, np.sqrt(s))
        data[k, 6] = radius
    return data
