"""Rotation matrices in any dimension, for :meth:`ndpack.Oracle.rotate`."""

from __future__ import annotations

import numpy as np

from ..errors import ShapeError


def rotation(dim: int, angle: float, axes: tuple[int, int] = (0, 1)) -> np.ndarray:
    """The ``(dim, dim)`` rotation by ``angle`` radians in the plane of two coordinate ``axes``.

    In 3D, ``axes=(0, 1)`` turns about z, ``(1, 2)`` about x and ``(2, 0)`` about y. Compose
    several with ``@`` for any rotation.
    """
    i, j = axes
    if not (0 <= i < dim and 0 <= j < dim and i != j):
        raise ShapeError(f"axes must be two different axes of a {dim}-D space, got {axes}")
    matrix = np.eye(dim)
    cos, sin = np.cos(angle), np.sin(angle)
    matrix[i, i] = matrix[j, j] = cos
    matrix[i, j], matrix[j, i] = -sin, sin
    return matrix
