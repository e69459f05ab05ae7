"""The exact generalised winding number, by summing every triangle's solid angle in NumPy.

The reference the packing's mesh oracle is checked against: no tree, no far-field approximation,
no compiled code, nothing shared with :mod:`ndpack.meshes.kernels`. It costs points x triangles,
so it is for checks (:func:`ndpack.verify` with ``independent=True``), not for packing.
"""

from __future__ import annotations

import numpy as np

#: Point-triangle pairs evaluated at once (about 100 MB of temporaries).
CHUNK_PAIRS = 1_000_000


def winding_number(triangles: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Generalised winding numbers of ``points`` with respect to ``triangles``.

    Each triangle's signed solid angle seen from a point by Van Oosterom and Strackee's formula
    (1983), ``tan(omega / 2) = det[a, b, c] / (|a||b||c| + (a.b)|c| + (a.c)|b| + (b.c)|a|)`` with
    the corners relative to the point, summed and divided by ``4 pi``.

    Parameters
    ----------
    triangles : (f, 3, 3) float64
        Corners, counter-clockwise seen from outside.
    points : (n, 3) float64

    Returns
    -------
    (n,) float64
        1 inside a closed outward surface, 0 outside, fractional near an open surface's holes.
    """
    triangles = np.asarray(triangles, dtype=np.float64)
    points = np.asarray(points, dtype=np.float64)
    total = np.zeros(len(points))
    step = max(1, CHUNK_PAIRS // max(len(triangles), 1))
    for start in range(0, len(points), step):
        corners = triangles[None, :, :, :] - points[start:start + step, None, None, :]  # (m, f, 3, 3)
        a, b, c = corners[:, :, 0], corners[:, :, 1], corners[:, :, 2]
        la, lb, lc = (np.linalg.norm(x, axis=2) for x in (a, b, c))
        numerator = np.einsum("mfi,mfi->mf", a, np.cross(b, c))
        denominator = (la * lb * lc + np.einsum("mfi,mfi->mf", a, b) * lc
                       + np.einsum("mfi,mfi->mf", a, c) * lb + np.einsum("mfi,mfi->mf", b, c) * la)
        total[start:start + step] = 2.0 * np.arctan2(numerator, denominator).sum(axis=1)
    return total / (4.0 * np.pi)

