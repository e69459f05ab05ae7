"""Constructive solid geometry on distance oracles of equal dimension.

Boolean nodes (``|``, ``&``, ``-``, ``~``), rigid motions, uniform scaling, offsets, shells and
a smooth union. Each node keeps the protocol of :mod:`ndpack.oracle`: the result is 1-Lipschitz
with the right sign, and its exactness flags follow from its children's:

==============  ======================================  =====================================
node            exact inside when                       exact outside when
==============  ======================================  =====================================
union           never (a lower bound)                   every child is exact outside
intersection    every child is exact inside             never (a lower bound)
a - b           a exact inside and b exact outside      never
complement      the child is exact outside              the child is exact inside
translate,      as the child                            as the child
rotate, scale
dilate (r > 0)  child convex and exact on both sides    the child is exact outside
erode (r < 0)   the child is exact inside               never
shell           never                                   never
smooth union    never (a bound of the filleted shape)   never
==============  ======================================  =====================================

Each node's ``_kernel`` writes the same formula as its ``_distance`` as a small generated kernel
function (see :mod:`ndpack.kernels.program`) that calls its children's kernels; transforms keep
their numbers (offset, centre, matrix, factor) in the parameters, not in the program text.
"""

from __future__ import annotations

import numpy as np

from ..errors import ShapeError
from ..kernels import tape as ops
from ..oracle import Oracle, as_vector, check_compatible, operation, parts
from .empty import Empty, Everything, is_special

INFINITE = np.inf


def check_parts(node: str, *children: Oracle) -> int:
    """The children's common dimension; a clear error for a child that is an empty set or all
    of space, which no node holds (:class:`_Node` builds such a tree by the operators, which
    leave it out; see :mod:`ndpack.shapes.empty`)."""
    dim = check_compatible(*children)
    for child in children:
        if is_special(child):
            raise ShapeError(f"{node} cannot hold {child!r} ({getattr(child, 'reason', '')}); combine shapes with "
                             "|, &, - and ~, which leave an empty part out")
    return dim


def common_box(shapes) -> np.ndarray | None:
    """(2, d): the box that the bounding boxes of ``shapes`` share; None where they do not overlap."""
    bounds = np.stack([shape.bounds for shape in shapes])
    box = np.stack([bounds[:, 0].max(axis=0), bounds[:, 1].min(axis=0)])
    return None if np.any(box[0] >= box[1]) else box


class _Built(type):
    """The metaclass of :class:`_Node`: calling a node's class builds, where the node would hold
    an empty part, what the operator builds (not through ``__new__``, after which Python would
    run ``__init__`` again on an operator's result of the same class, with the empty part)."""

    def __call__(cls, *args, **kwargs):
        parts = [value for value in (*args, *kwargs.values()) if isinstance(value, Oracle)]
        if _leaves_out(cls, parts):
            return cls._by_operator(*args, **kwargs)
        return super().__call__(*args, **kwargs)


class _Node(Oracle, metaclass=_Built):
    """A CSG node built by its class: where a part is an empty set or all of space (or the parts
    of an intersection have boxes apart), the class builds what the operator does (``Union(a,
    empty)`` is ``a | empty``, that is ``a``), so that an empty *part* of a tree is a valid empty
    set whichever way the tree is written; only an empty *whole* shape is an error, where it is
    packed. Subclasses give ``_by_operator`` (the operator form, with the class's parameters)
    and ``_least_parts`` (fewer shapes than that: the class's own error)."""

    _least_parts = 1


def _leaves_out(cls, parts) -> bool:
    """Whether a node of ``cls`` over ``parts`` is built by its operator instead (see :class:`_Node`).
    Parts of different dimensions go to the class, which says so."""
    if len(parts) < cls._least_parts or len({part.dim for part in parts}) != 1:
        return False
    if any(is_special(part) for part in parts):
        return True
    return issubclass(cls, Intersection) and common_box(parts) is None


class _Boolean(_Node):
    """Shared code of n-ary min/max nodes: evaluate all children, keep the active one per point."""

    _least_parts = 2

    _pick = staticmethod(np.argmin)
    _combine = "min"  # the same in the kernel language

    def __init__(self, *children: Oracle):
        if len(children) < 2:
            raise ShapeError(f"{type(self).__name__} needs at least two shapes, got {len(children)}")
        self.dim = check_parts(type(self).__name__, *children)
        flat: list[Oracle] = []
        for child in children:  # (a | b) | c is stored as one node of three children
            flat.extend(getattr(child, "children") if type(child) is type(self) else [child])
        self.children = tuple(flat)

    def _distance(self, points):
        distances = np.stack([child._distance(points) for child in self.children])
        return distances[self._pick(distances, axis=0), np.arange(len(points))]

    def _distance_and_gradient(self, points):
        pairs = [child._distance_and_gradient(points) for child in self.children]
        distances = np.stack([d for d, _ in pairs])
        gradients = np.stack([g for _, g in pairs])
        active = self._pick(distances, axis=0)
        rows = np.arange(len(points))
        return distances[active, rows], gradients[active, rows]

    def _gradient(self, points):
        return self._distance_and_gradient(points)[1]

    def _kernel(self, program):
        calls = ", ".join(f"{program.shape(child)}(p, prm)" for child in self.children)
        return program.define(f"def _(p, prm):\n    return {self._combine}({calls})\n")

    def _tape(self, tape):
        # Nested nodes of the same kind are one n-ary node (min and max are associative and
        # exact), so a chain a | b | c needs two values on the tape's stack, not one per level.
        operands = self._operands()
        tape.add(operands[0])
        for child in operands[1:]:
            tape.add(child)
            tape.operation(ops.MIN if self._combine == "min" else ops.MAX)

    def _operands(self):
        """The children, with those of children of this very kind in their place."""
        out = []
        for child in self.children:
            out.extend(child._operands() if type(child) is type(self) else [child])
        return out

    def __repr__(self):
        return f"{type(self).__name__}({', '.join(map(repr, self.children))})"


class Union(_Boolean):
    """Points inside any child: ``min`` of the distances. An empty child is left out, as ``|``
    does: ``Union(a, empty)`` is ``a``."""

    _pick = staticmethod(np.argmin)
    _combine = "min"
    _by_operator = staticmethod(lambda *children: children[0].union(*children[1:]))

    def __init__(self, *children: Oracle):
        super().__init__(*children)
        self.exact_inside = False
        self.exact_outside = all(c.exact_outside for c in self.children)
        self.convex = False
        bounds = np.stack([c.bounds for c in self.children])
        self._bounds = np.stack([bounds[:, 0].min(axis=0), bounds[:, 1].max(axis=0)])


class Intersection(_Boolean):
    """Points inside every child: ``max`` of the distances. With an empty child, or children whose
    bounding boxes do not overlap, it is an empty set, as ``&`` makes it: valid as a part of a
    tree, refused where it is packed as a whole."""

    _pick = staticmethod(np.argmax)
    _combine = "max"
    _by_operator = staticmethod(lambda *children: children[0].intersection(*children[1:]))

    def __init__(self, *children: Oracle):
        super().__init__(*children)
        self.exact_inside = all(c.exact_inside for c in self.children)
        self.exact_outside = False
        self.convex = all(c.convex for c in self.children)
        bounds = common_box(self.children)
        if bounds is None:  # only where the metaclass (_Built) was bypassed: it builds an empty set
            raise ShapeError(
                f"the intersection of {', '.join(map(repr, self.children))} is empty: their "
                "bounding boxes do not overlap"
            )
        self._bounds = bounds


class Complement(_Node):
    """Everything outside the child: the distance negated."""

    _by_operator = staticmethod(lambda child: child.complement())

    def __init__(self, child: Oracle):
        self.dim = check_parts(type(self).__name__, child)
        self.child = child
        self.exact_inside = child.exact_outside
        self.exact_outside = child.exact_inside
        self._bounds = np.stack([np.full(self.dim, -INFINITE), np.full(self.dim, INFINITE)])

    def _distance(self, points):
        return -self.child._distance(points)

    def _distance_and_gradient(self, points):
        distances, gradients = self.child._distance_and_gradient(points)
        return -distances, -gradients

    def _gradient(self, points):
        return -self.child._gradient(points)

    def _exact_volume(self):
        return np.inf

    def _kernel(self, program):
        return program.define(f"def _(p, prm):\n    return -{program.shape(self.child)}(p, prm)\n")

    def _tape(self, tape):
        tape.add(self.child)
        tape.operation(ops.NEGATE)

    def complement(self) -> Oracle:
        return self.child

    def __repr__(self):
        return f"~{self.child!r}"


class Difference(_Node):
    """Points inside ``a`` and outside ``b``: ``max(a, -b)``. An empty ``b`` leaves ``a``, an empty
    ``a`` is empty, as ``-`` does."""

    _least_parts = 2
    _by_operator = staticmethod(lambda a, b: a.difference(b))

    def __init__(self, a: Oracle, b: Oracle):
        self.dim = check_parts(type(self).__name__, a, b)
        self.a, self.b = a, b
        self.exact_inside = a.exact_inside and b.exact_outside
        self.exact_outside = False
        self._bounds = a.bounds.copy()

    def _distance(self, points):
        return np.maximum(self.a._distance(points), -self.b._distance(points))

    def _distance_and_gradient(self, points):
        da, ga = self.a._distance_and_gradient(points)
        db, gb = self.b._distance_and_gradient(points)
        use_b = -db > da
        return np.where(use_b, -db, da), np.where(use_b[:, None], -gb, ga)

    def _gradient(self, points):
        return self._distance_and_gradient(points)[1]

    def _kernel(self, program):
        a, b = program.shape(self.a), program.shape(self.b)
        return program.define(f"def _(p, prm):\n    return max({a}(p, prm), -{b}(p, prm))\n")

    def _tape(self, tape):
        tape.add(self.a)
        tape.add(self.b)
        tape.operation(ops.DIFFERENCE)

    def __repr__(self):
        return f"({self.a!r} - {self.b!r})"


class _Transformed(_Node):
    """A child seen through a map: subclasses define ``_to_child`` and ``_from_child_gradient``."""

    def __init__(self, child: Oracle):
        self.dim = check_parts(type(self).__name__, child)
        self.child = child
        self.exact_inside = child.exact_inside
        self.exact_outside = child.exact_outside
        self.convex = child.convex

    def _distance(self, points):
        return self._distance_factor * self.child._distance(self._to_child(points))

    def _distance_and_gradient(self, points):
        distances, gradients = self.child._distance_and_gradient(self._to_child(points))
        return self._distance_factor * distances, self._from_child_gradient(gradients)

    def _gradient(self, points):
        return self._distance_and_gradient(points)[1]

    _distance_factor = 1.0

    def _from_child_gradient(self, gradients):
        return gradients

    def _exact_volume(self):
        volume = self.child._exact_volume()
        return None if volume is None else volume * self._distance_factor**self.dim


class Translate(_Transformed):
    """The child moved by ``offset`` (dim,), kept as ``shift`` (an attribute named ``offset``
    would hide the :meth:`offset` method of every shape)."""

    _by_operator = staticmethod(lambda child, offset: child.translate(offset))

    def __init__(self, child: Oracle, offset):
        super().__init__(child)
        self.shift = as_vector(offset, self.dim, "translation offset")
        self._bounds = child.bounds + self.shift

    def _to_child(self, points):
        return points - self.shift

    def _kernel(self, program):
        o = program.add_params(self.shift)
        child = program.shape(self.child)
        return program.define(
            "def _(p, prm):\n"
            "    q = point()\n"
            "    for i in range(D):\n"
            f"        q[i] = p[i] - prm[{o} + i]\n"
            f"    return {child}(q, prm)\n"
        )

    def _tape(self, tape):
        with tape.transformed(np.eye(self.dim), -self.shift):
            tape.add(self.child)

    def __repr__(self):
        return f"{self.child!r}.translate({self.shift.tolist()})"


class Rotate(_Transformed):
    """The child rotated (or reflected) by an orthogonal ``matrix`` (dim, dim) about ``center``."""

    _by_operator = staticmethod(lambda child, matrix, center=None: child.rotate(matrix, center))

    def __init__(self, child: Oracle, matrix, center=None):
        super().__init__(child)
        matrix = np.asarray(matrix, dtype=np.float64)
        if matrix.shape != (self.dim, self.dim):
            raise ShapeError(f"rotation matrix must be ({self.dim}, {self.dim}), got {matrix.shape}")
        error = np.abs(matrix.T @ matrix - np.eye(self.dim)).max()
        if not error < 1e-9:
            raise ShapeError(
                f"rotation matrix is not orthogonal (|M^T M - I| = {error:.2g}); a distance "
                "survives only rotations and reflections: use scale_by() for uniform scaling"
            )
        self.matrix = matrix
        self.center = np.zeros(self.dim) if center is None else as_vector(center, self.dim, "center")
        if child.is_bounded:
            # The AABB of a rotated box: centre maps, half-extents go through |M|.
            lower, upper = child.bounds
            middle = self.matrix @ ((lower + upper) / 2 - self.center) + self.center
            half = np.abs(self.matrix) @ ((upper - lower) / 2)
            self._bounds = np.stack([middle - half, middle + half])
        else:
            self._bounds = np.stack([np.full(self.dim, -INFINITE), np.full(self.dim, INFINITE)])

    def _to_child(self, points):
        # Row vectors: x_child = M^T (x - c) + c  <=>  (x - c) @ M + c.
        return (points - self.center) @ self.matrix + self.center

    def _from_child_gradient(self, gradients):
        return gradients @ self.matrix.T

    def _kernel(self, program):
        # [center (D), matrix (D x D, row-major)]: q_j = sum_i (p_i - c_i) M_ij + c_j.
        o = program.add_params([*self.center, *self.matrix.ravel()])
        child = program.shape(self.child)
        return program.define(
            "def _(p, prm):\n"
            "    q = point()\n"
            "    for j in range(D):\n"
            "        s = 0.0\n"
            "        for i in range(D):\n"
            f"            s += (p[i] - prm[{o} + i]) * prm[{o} + D + i * D + j]\n"
            f"        q[j] = s + prm[{o} + j]\n"
            f"    return {child}(q, prm)\n"
        )

    def _tape(self, tape):
        # q = (p - c) M + c, as a column: M^T p + (c - M^T c).
        with tape.transformed(self.matrix.T, self.center - self.matrix.T @ self.center):
            tape.add(self.child)

    def __repr__(self):
        return f"{self.child!r}.rotate(...)"


class Scale(_Transformed):
    """The child scaled uniformly by ``factor`` > 0 about ``center``: ``s * f((x - c) / s + c)``."""

    _by_operator = staticmethod(lambda child, factor, center=None: child.scale_by(factor, center))

    def __init__(self, child: Oracle, factor: float, center=None):
        super().__init__(child)
        factor = float(factor)
        if not (np.isfinite(factor) and factor > 0):
            raise ShapeError(
                f"scale factor must be a positive number, got {factor}; for a mirror image use "
                "rotate() with a reflection matrix"
            )
        self.factor = factor
        self._distance_factor = factor
        self.center = np.zeros(self.dim) if center is None else as_vector(center, self.dim, "center")
        self._bounds = (child.bounds - self.center) * factor + self.center

    def _to_child(self, points):
        return (points - self.center) / self.factor + self.center

    def _kernel(self, program):
        # [center (D), factor]: s * f((x - c) / s + c).
        o = program.add_params([*self.center, self.factor])
        child = program.shape(self.child)
        return program.define(
            "def _(p, prm):\n"
            f"    factor = prm[{o} + D]\n"
            "    q = point()\n"
            "    for i in range(D):\n"
            f"        q[i] = (p[i] - prm[{o} + i]) / factor + prm[{o} + i]\n"
            f"    return factor * {child}(q, prm)\n"
        )

    def _tape(self, tape):
        # q = (p - c) / s + c; the distance times s.
        with tape.transformed(np.eye(self.dim) / self.factor, self.center - self.center / self.factor, self.factor):
            tape.add(self.child)

    def __repr__(self):
        return f"{self.child!r}.scale_by({self.factor})"


class Offset(_Node):
    """The child dilated by ``amount`` > 0 or eroded by ``-amount``: ``f - amount``."""

    _by_operator = staticmethod(lambda child, amount: child.offset(amount))

    def __init__(self, child: Oracle, amount: float):
        self.dim = check_parts(type(self).__name__, child)
        self.child = child
        self.amount = float(amount)
        if not np.isfinite(self.amount):
            raise ShapeError(f"offset amount must be finite, got {amount}")
        self.convex = child.convex
        if self.amount >= 0:
            self.exact_inside = child.convex and child.exact_inside and child.exact_outside
            self.exact_outside = child.exact_outside
            self._bounds = child.bounds + np.array([[-self.amount], [self.amount]])
        else:
            self.exact_inside = child.exact_inside
            self.exact_outside = False
            self._bounds = child.bounds.copy()

    def _distance(self, points):
        return self.child._distance(points) - self.amount

    def _distance_and_gradient(self, points):
        distances, gradients = self.child._distance_and_gradient(points)
        return distances - self.amount, gradients

    def _gradient(self, points):
        return self.child._gradient(points)

    def _kernel(self, program):
        o = program.add_params([self.amount])
        child = program.shape(self.child)
        return program.define(f"def _(p, prm):\n    return {child}(p, prm) - prm[{o}]\n")

    def _tape(self, tape):
        tape.add(self.child)
        tape.operation(ops.OFFSET, self.amount)

    def __repr__(self):
        return f"{self.child!r}.offset({self.amount})"


class Shell(_Node):
    """The layer of ``thickness`` centred on the child's boundary: ``|f| - thickness / 2``."""

    _by_operator = staticmethod(lambda child, thickness: child.shell(thickness))

    def __init__(self, child: Oracle, thickness: float):
        self.dim = check_parts(type(self).__name__, child)
        self.child = child
        self.thickness = float(thickness)
        if not (np.isfinite(self.thickness) and self.thickness > 0):
            raise ShapeError(f"shell thickness must be positive, got {thickness}")
        self._bounds = child.bounds + np.array([[-self.thickness / 2], [self.thickness / 2]])

    def _distance(self, points):
        return np.abs(self.child._distance(points)) - self.thickness / 2

    def _distance_and_gradient(self, points):
        distances, gradients = self.child._distance_and_gradient(points)
        sign = np.where(distances < 0, -1.0, 1.0)
        return np.abs(distances) - self.thickness / 2, gradients * sign[:, None]

    def _gradient(self, points):
        return self._distance_and_gradient(points)[1]

    def _kernel(self, program):
        o = program.add_params([self.thickness / 2])
        child = program.shape(self.child)
        return program.define(f"def _(p, prm):\n    return abs({child}(p, prm)) - prm[{o}]\n")

    def _tape(self, tape):
        tape.add(self.child)
        tape.operation(ops.SHELL, self.thickness / 2)

    def __repr__(self):
        return f"{self.child!r}.shell({self.thickness})"


class SmoothUnion(_Node):
    """Union of ``a`` and ``b`` with a fillet of width ``blend`` (polynomial smooth minimum).

    ``h = clip(1/2 + (b - a) / (2 k), 0, 1)``, ``f = h a + (1 - h) b - k h (1 - h)``. Its
    gradient is ``h grad a + (1 - h) grad b``, so it stays 1-Lipschitz: a lower bound of the
    distance to its own (filleted) boundary, never exact.
    """

    _least_parts = 2
    _by_operator = staticmethod(lambda a, b, blend: a.smooth_union(b, blend))

    def __init__(self, a: Oracle, b: Oracle, blend: float):
        self.dim = check_parts(type(self).__name__, a, b)
        self.a, self.b = a, b
        self.blend = float(blend)
        if not (np.isfinite(self.blend) and self.blend > 0):
            raise ShapeError(f"smooth union blend must be positive, got {blend}; use | for a sharp union")
        union = np.stack([a.bounds, b.bounds])
        # The fillet adds material where both distances are below blend / 4.
        pad = self.blend / 4
        self._bounds = np.stack([union[:, 0].min(axis=0) - pad, union[:, 1].max(axis=0) + pad])

    def _weights(self, da, db):
        return np.clip(0.5 + (db - da) / (2 * self.blend), 0.0, 1.0)

    def _distance(self, points):
        da, db = self.a._distance(points), self.b._distance(points)
        h = self._weights(da, db)
        return h * da + (1 - h) * db - self.blend * h * (1 - h)

    def _distance_and_gradient(self, points):
        da, ga = self.a._distance_and_gradient(points)
        db, gb = self.b._distance_and_gradient(points)
        h = self._weights(da, db)
        distances = h * da + (1 - h) * db - self.blend * h * (1 - h)
        gradients = h[:, None] * ga + (1 - h)[:, None] * gb
        norms = np.linalg.norm(gradients, axis=1, keepdims=True)
        # Opposite child gradients can cancel; keep the raw one there rather than divide by ~0.
        gradients = np.where(norms > 1e-12, gradients / np.maximum(norms, 1e-300), ga)
        return distances, gradients

    def _gradient(self, points):
        return self._distance_and_gradient(points)[1]

    def _kernel(self, program):
        o = program.add_params([self.blend])
        a, b = program.shape(self.a), program.shape(self.b)
        return program.define(
            "def _(p, prm):\n"
            f"    da = {a}(p, prm)\n"
            f"    db = {b}(p, prm)\n"
            f"    k = prm[{o}]\n"
            "    h = min(max(0.5 + (db - da) / (2.0 * k), 0.0), 1.0)\n"
            "    return h * da + (1.0 - h) * db - k * h * (1.0 - h)\n"
        )

    def _tape(self, tape):
        tape.add(self.a)
        tape.add(self.b)
        tape.operation(ops.SMOOTH, self.blend)

    def __repr__(self):
        return f"{self.a!r}.smooth_union({self.b!r}, {self.blend})"


# ---------------------------------------------------------------------------------- the operations
# What Oracle's methods and operators build (ndpack.oracle.OPERATIONS), registered here, where the
# node classes are. An empty part is left out as the tree is built: a - empty is a, a & empty is
# empty, so no node holds one.
@operation("union")
def union(shape: Oracle, *others) -> Oracle:
    found = parts(shape, others)  # shape is neither Empty nor Everything: they have their own
    for part in found:
        if isinstance(part, Everything):
            return part
    kept = [part for part in found if not isinstance(part, Empty)]
    return kept[0] if len(kept) == 1 else Union(*kept)


@operation("intersection")
def intersection(shape: Oracle, *others) -> Oracle:
    found = parts(shape, others)
    for part in found:
        if isinstance(part, Empty):
            return part
    kept = [part for part in found if not isinstance(part, Everything)]
    if len(kept) == 1:
        return kept[0]
    if common_box(kept) is None:
        return Empty(shape.dim, f"the intersection of {', '.join(map(repr, kept))} is empty: their bounding "
                                "boxes do not overlap")
    return Intersection(*kept)


@operation("difference")
def difference(shape: Oracle, *others) -> Oracle:
    result = shape
    for other in parts(shape, others)[1:]:
        if isinstance(result, Empty) or isinstance(other, Empty):
            continue
        if isinstance(other, Everything):
            result = Empty(shape.dim, f"{result!r} less all of space ({other.reason})")
        else:
            result = Difference(result, other)
    return result


@operation("smooth_union")
def smooth_union(shape: Oracle, other, blend: float) -> Oracle:
    other = parts(shape, (other,))[1]
    if is_special(other):  # nothing to blend with: the union alone
        return shape.union(other)
    return SmoothUnion(shape, other, blend)


operation("complement")(Complement)
operation("translate")(Translate)
operation("rotate")(Rotate)
operation("scale_by")(Scale)
operation("offset")(Offset)
operation("shell")(Shell)
