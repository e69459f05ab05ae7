"""Analytic shapes, CSG and plug-ins: every one a distance oracle (see :mod:`ndpack.oracle`)."""

from .csg import (
    Complement,
    Difference,
    Intersection,
    Offset,
    Rotate,
    Scale,
    Shell,
    SmoothUnion,
    Translate,
    Union,
)
from .plugin import Function, plugin
from . import adapters  # noqa: F401  (registers as_oracle for Oracle's operators)
from .mesh import TriangleMesh
from .periodic import Periodic
from .polygon import Polygon
from .scalar import ScalarFunction, scalar_plugin
from .primitives import (
    Ball,
    Box,
    Capsule,
    ConvexPolytope,
    Cylinder,
    Ellipsoid,
    HalfSpace,
    RoundedBox,
    Simplex,
    Slab,
    Torus,
)

__all__ = [
    "Ball", "Box", "Capsule", "Complement", "ConvexPolytope", "Cylinder", "Difference",
    "Ellipsoid", "Function", "HalfSpace", "Intersection", "Offset", "Periodic", "Polygon", "Rotate",
    "RoundedBox", "Scale", "ScalarFunction", "Shell", "Simplex", "Slab", "SmoothUnion", "Torus",
    "Translate", "TriangleMesh", "Union", "plugin", "scalar_plugin",
]
