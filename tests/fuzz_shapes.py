"""Random shape trees for fuzzing, in 2-D to 6-D, each paired with an independent reference.

A tree is drawn as the source text of an ndpack expression (``(nd.Ball([...], 0.5) - ...)``),
so that a failing case can be pasted into a regression test as it is, and its
:class:`~fuzz_reference.Reference` is built from the same numbers by :mod:`fuzz_reference`,
never from the ndpack object. :func:`case` draws case ``index`` of a run from ``seed`` alone.

Leaves: every ndpack primitive (the torus in 3-D; half-spaces and slabs as cuts), trimesh
primitive meshes and manifold3d solids in 3-D, ndpack polygons (with holes and islands), shapely
geometries and manifold3d cross-sections in 2-D. Nodes: union (binary and n-ary), intersection,
cuts by half-spaces and slabs, difference, complement (as ``a & ~b``), smooth union, offset,
shell, translate, rotate (reflections too) and uniform scaling, through both the operators and
the classes; other libraries' objects are moved and combined by their own library where ndpack
cannot take them (a manifold3d solid has no ``.rotate`` of ndpack's).

Extra leaves (``extended=True``, the default of :func:`case`): user plug-ins in every dimension
(:class:`ndpack.ScalarFunction` of :mod:`fuzz_plugins`, or :class:`ndpack.Function` of a NumPy
lambda; exact balls and boxes) and, in 3-D, open meshes (a trimesh primitive less a few triangles
that share no vertex, loaded with ``holes="cap"``). They replace a leaf drawn as before, from a
second random stream, so that every tree without one is the tree drawn before they existed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import fuzz_reference as ref

#: Share of each dimension among the trees.
DIMENSIONS = {2: 0.25, 3: 0.3, 4: 0.2, 5: 0.15, 6: 0.1}
#: Each leaf's weight (the dimension-bound ones only in their dimension).
LEAF_WEIGHTS = {
    "ball": 3, "box": 3, "rounded_box": 2, "capsule": 2, "cylinder": 2, "polytope": 2, "simplex": 2,
    "ellipsoid": 2, "torus": 3, "trimesh": 4, "manifold": 4, "polygon": 4, "shapely": 3, "cross_section": 4,
}
ONLY_IN = {"torus": 3, "trimesh": 3, "manifold": 3, "polygon": 2, "shapely": 2, "cross_section": 2}
#: Each inner node's weight.
NODE_WEIGHTS = {
    "union": 3, "union_n": 1, "intersection": 2, "cut": 2, "difference": 3, "complement": 1,
    "smooth_union": 2, "offset": 2, "shell": 1, "translate": 1, "rotate": 2, "scale": 1,
}
#: Leaves whose exact signed distance the reference knows (for offset, shell, smooth union).
EXACT_LEAVES = ("ball", "box", "rounded_box", "capsule", "cylinder", "torus")
#: Extra leaves: the share of leaves replaced by one, and each one's weight (open meshes in 3-D).
EXTRA_SHARE = 0.15
EXTRA_WEIGHTS = {"plugin": 1, "open_mesh": 2}
#: Grid cells along the longest side, by dimension (None: ndpack's default of about 32,768 cells).
GRIDS = {2: (24, 48, None), 3: (10, 16, None), 4: (6, 9), 5: (4, 6), 6: (3, 4)}


@dataclass
class Part:
    """A drawn (sub)tree: its source text, reference and kinds; ``foreign`` names the library
    of an object that is not an ndpack shape (``"trimesh"``, ``"manifold"``, ``"cross_section"``,
    ``"shapely"``), None for ndpack shapes."""

    code: str
    reference: ref.Reference
    kinds: frozenset = frozenset()
    foreign: str | None = None


@dataclass
class Case:
    """One fuzzing case: a tree and the packing parameters drawn with it.

    Attributes
    ----------
    seed, index : int
        What :func:`case` drew it from.
    code : str
        The tree's source text (see :func:`build`).
    reference : fuzz_reference.Reference
    kinds : list of str
        Leaf and node kinds in the tree.
    n : int
        Spheres to pack.
    grid : int or None
        Cells along the longest side.
    pack_seed : int
    """

    seed: int
    index: int
    code: str
    reference: ref.Reference
    kinds: list
    n: int
    grid: int | None
    pack_seed: int

    @property
    def dim(self) -> int:
        return self.reference.dim

    def build(self):
        return build(self.code)


def build(code: str):
    """Evaluate a tree's source text, with ``nd``, ``np``, ``trimesh``, ``m3d``, ``shapely`` and
    ``plugins`` (:mod:`fuzz_plugins`)."""
    import manifold3d as m3d
    import shapely
    import shapely.affinity  # moves shapely geometries
    import trimesh

    import fuzz_plugins
    import ndpack as nd

    return eval(code, {"nd": nd, "np": np, "trimesh": trimesh, "m3d": m3d, "shapely": shapely,
                       "plugins": fuzz_plugins})


def text(values) -> str:
    """Numbers as source text that reads back to the same float64 values."""
    return repr(np.asarray(values, dtype=np.float64).tolist())


def num(value) -> str:
    return repr(float(value))


def foreign_reference(kind: str, code: str) -> ref.Reference:
    """The reference of another library's object, from that object (its mesh or geometry)."""
    obj = build(code)
    if kind == "trimesh":
        return ref.winding_mesh(obj.vertices, obj.faces)
    if kind == "manifold":
        return ref.manifold_solid(obj)
    if kind == "cross_section":
        return ref.cross_section(obj)
    return ref.shapely_region(obj)


def orthogonal(rng, dim: int, reflect: bool = False) -> np.ndarray:
    """A random rotation (a reflection when ``reflect``), (dim, dim)."""
    q, r = np.linalg.qr(rng.normal(size=(dim, dim)))
    q = q * np.sign(np.diag(r))
    if (np.linalg.det(q) < 0) != reflect:
        q[:, 0] = -q[:, 0]
    return q


class Drawer:
    """Draws the parts of one tree in one dimension from a numpy Generator."""

    def __init__(self, rng: np.random.Generator, dim: int, extra: np.random.Generator | None = None):
        self.rng, self.dim, self.extra = rng, dim, extra

    def choose(self, weights: dict) -> str:
        names = list(weights)
        p = np.array([weights[k] for k in names], dtype=float)
        return names[self.rng.choice(len(names), p=p / p.sum())]

    def point(self, spread=0.5) -> np.ndarray:
        return self.rng.uniform(-spread, spread, self.dim)

    def unit(self) -> np.ndarray:
        if self.rng.random() < 0.2:  # axis-aligned normals take other code paths (bounds)
            return np.eye(self.dim)[self.rng.integers(self.dim)] * self.rng.choice([-1.0, 1.0])
        v = self.rng.normal(size=self.dim)
        return v / np.linalg.norm(v)

    # ------------------------------------------------------------------ trees
    def tree(self, depth: int) -> Part:
        if depth == 0 or self.rng.random() < 0.3:
            return self.leaf()
        kind = self.choose(NODE_WEIGHTS)
        return getattr(self, "node_" + kind)(depth - 1)

    def leaf(self, exact: bool = False) -> Part:
        names = EXACT_LEAVES if exact else LEAF_WEIGHTS
        weights = {k: LEAF_WEIGHTS[k] for k in names if ONLY_IN.get(k, self.dim) == self.dim}
        kind = self.choose(weights)
        part = getattr(self, "leaf_" + kind)()
        if self.extra is not None and self.extra.random() < EXTRA_SHARE:
            # Drawn above all the same, so that the rest of the tree is as without extra leaves.
            extras = {k: w for k, w in EXTRA_WEIGHTS.items() if k == "plugin" or (self.dim == 3 and not exact)}
            names = list(extras)
            kind = names[self.extra.choice(len(names), p=np.array([extras[k] for k in names]) / sum(extras.values()))]
            part = getattr(self, "extra_" + kind)(self.extra)
            kind = next(iter(part.kinds))
        return Part(part.code, part.reference, frozenset({kind}), part.foreign)

    def exact(self, depth: int) -> Part:
        """An exact leaf, perhaps moved: the reference knows its signed distance."""
        part = self.leaf(exact=True)
        for _ in range(self.rng.integers(0, depth + 1)):
            part = getattr(self, "node_" + self.choose({"translate": 1, "rotate": 2, "scale": 1}))(0, part)
        return part

    # ------------------------------------------------------------------ primitives
    def leaf_ball(self):
        c, r = self.point(), self.rng.uniform(0.3, 0.9)
        return Part(f"nd.Ball({text(c)}, {num(r)})", ref.ball(c, r))

    def _corners(self):
        c = self.point()
        lower, upper = c - self.rng.uniform(0.2, 0.8, self.dim), c + self.rng.uniform(0.2, 0.8, self.dim)
        if self.rng.random() < 0.1:  # a thin plate, thinner than the grid's cells
            axis = self.rng.integers(self.dim)
            upper[axis] = lower[axis] + self.rng.uniform(0.005, 0.05)
        return lower, upper

    def leaf_box(self):
        lower, upper = self._corners()
        return Part(f"nd.Box({text(lower)}, {text(upper)})", ref.box(lower, upper))

    def leaf_rounded_box(self):
        lower, upper = self._corners()
        r = self.rng.uniform(0.05, 0.45) * float((upper - lower).min())
        return Part(f"nd.RoundedBox({text(lower)}, {text(upper)}, {num(r)})", ref.rounded_box(lower, upper, r))

    def leaf_capsule(self):
        a = self.point()
        b = a.copy() if self.rng.random() < 0.1 else a + self.unit() * self.rng.uniform(0.1, 0.9)
        r = self.rng.uniform(0.1, 0.5)
        return Part(f"nd.Capsule({text(a)}, {text(b)}, {num(r)})", ref.capsule(a, b, r))

    def leaf_cylinder(self):
        a = self.point()
        b = a + self.unit() * self.rng.uniform(0.2, 1.2)
        r = self.rng.uniform(0.1, 0.5)
        return Part(f"nd.Cylinder({text(a)}, {text(b)}, {num(r)})", ref.cylinder(a, b, r))

    def leaf_polytope(self):
        """The facets of a turned regular simplex about a centre, and a few more planes."""
        d, c = self.dim, self.point()
        centred = np.eye(d + 1) - 1.0 / (d + 1)
        basis = np.linalg.svd(centred)[0][:, :d]  # an orthonormal basis of the sum-zero plane
        simplex = centred @ basis
        simplex = simplex / np.linalg.norm(simplex, axis=1)[:, None] @ orthogonal(self.rng, d)
        extra = self.rng.normal(size=(self.rng.integers(0, d + 1), d))
        units = np.vstack([simplex, extra / np.linalg.norm(extra, axis=1)[:, None]])
        heights = self.rng.uniform(0.25, 0.8, len(units))
        lengths = self.rng.uniform(0.5, 2.0, len(units))  # ndpack normalises the rows
        normals, offsets = units * lengths[:, None], (units @ c + heights) * lengths
        # The simplex's own vertices bound the polytope: each is where d of its facets meet.
        vertices = np.array([np.linalg.solve(np.delete(units[: d + 1], j, 0),
                                             np.delete(units[: d + 1] @ c + heights[: d + 1], j))
                             for j in range(d + 1)])
        return Part(f"nd.ConvexPolytope({text(normals)}, {text(offsets)})", ref.polytope(normals, offsets, vertices))

    def leaf_simplex(self):
        c = self.point()
        while True:
            vertices = c + self.rng.normal(scale=0.6, size=(self.dim + 1, self.dim))
            if self.rng.random() < 0.1:  # a flat one
                vertices[:, self.rng.integers(self.dim)] *= 0.05
            edges = vertices[1:] - vertices[0]
            if abs(np.linalg.det(edges)) > 1e-6 * np.ptp(vertices, axis=0).max() ** self.dim:
                return Part(f"nd.Simplex({text(vertices)})", ref.simplex(vertices))

    def leaf_ellipsoid(self):
        c, radii = self.point(), self.rng.uniform(0.15, 0.9, self.dim)
        return Part(f"nd.Ellipsoid({text(c)}, {text(radii)})", ref.ellipsoid(c, radii))

    def leaf_torus(self):
        c, major = self.point(), self.rng.uniform(0.35, 0.8)
        minor = self.rng.uniform(0.1, 0.9) * major
        return Part(f"nd.Torus({text(c)}, {num(major)}, {num(minor)})", ref.torus(c, major, minor))

    def cutter(self, around: ref.Reference) -> Part:
        """A half-space or slab through the middle of ``around``'s box."""
        middle = around.box.mean(axis=0)
        extent = float(np.ptp(around.box, axis=0).max())
        n = self.unit() * self.rng.uniform(0.5, 2.0)
        p = middle + self.point(0.25) * extent
        if self.rng.random() < 0.5:
            return Part(f"nd.HalfSpace({text(n)}, {num(n @ p)})", ref.half_space(n, n @ p), frozenset({"half_space"}))
        unit = n / np.linalg.norm(n)
        width = self.rng.uniform(0.15, 0.6) * extent
        low = unit @ p - width / 2
        return Part(f"nd.Slab({text(n)}, {num(low)}, {num(low + width)})", ref.slab(n, low, low + width),
                    frozenset({"slab"}))

    # ------------------------------------------------------------------ other libraries
    def leaf_trimesh(self):
        code = self._trimesh_primitive(self.rng)
        part = Part(code, foreign_reference("trimesh", code), foreign="trimesh")
        if self.rng.random() < 0.5:  # as ndpack's own mesh shape, which takes ndpack's transforms
            return Part(f"nd.TriangleMesh.from_trimesh({code})", part.reference)
        return part

    def _trimesh_primitive(self, rng):
        """The source text of a closed trimesh primitive, turned and moved, drawn from ``rng``."""
        names = ["box", "icosphere", "cylinder", "capsule", "cone", "annulus", "torus"]
        kind = names[rng.choice(len(names), p=np.full(len(names), 1 / len(names)))]
        size = rng.uniform(0.4, 0.9)
        make = {
            "box": f"box(extents={text(rng.uniform(0.4, 1.4, 3))})",
            "icosphere": f"icosphere(subdivisions={rng.integers(1, 4)}, radius={num(size)})",
            "cylinder": f"cylinder(radius={num(size / 2)}, height={num(rng.uniform(0.4, 1.4))}, "
                        f"sections={rng.integers(8, 40)})",
            "capsule": f"capsule(height={num(rng.uniform(0.2, 1.0))}, radius={num(size / 2)}, count=[12, 12])",
            "cone": f"cone(radius={num(size / 2)}, height={num(rng.uniform(0.4, 1.2))}, "
                    f"sections={rng.integers(8, 40)})",
            "annulus": f"annulus(r_min={num(size / 3)}, r_max={num(size * 0.8)}, height={num(rng.uniform(0.2, 0.8))}, "
                       f"sections={rng.integers(12, 40)})",
            "torus": f"torus(major_radius={num(size * 0.7)}, minor_radius={num(size * 0.25)}, "
                     "major_sections=24, minor_sections=12)",
        }[kind]
        transform = np.eye(4)
        transform[:3, :3], transform[:3, 3] = orthogonal(rng, 3), rng.uniform(-0.4, 0.4, 3)
        return f"trimesh.creation.{make}.apply_transform(np.array({text(transform)}))"

    def _manifold_piece(self):
        rng = self.rng
        kind = self.choose({"cube": 2, "sphere": 2, "cylinder": 2})
        if kind == "cube":
            make = f"m3d.Manifold.cube({text(rng.uniform(0.3, 1.2, 3))}, True)"
        elif kind == "sphere":
            make = f"m3d.Manifold.sphere({num(rng.uniform(0.25, 0.7))}, {rng.integers(12, 48)})"
        else:
            make = (f"m3d.Manifold.cylinder({num(rng.uniform(0.4, 1.3))}, {num(rng.uniform(0.15, 0.5))}, "
                    f"{num(rng.uniform(0.0, 0.5))}, {rng.integers(8, 40)}, True)")
        return f"{make}.rotate({text(rng.uniform(0, 360, 3))}).translate({text(self.point(0.4))})"

    def leaf_manifold(self):
        code = self._manifold_piece()
        for _ in range(self.rng.integers(0, 3)):  # manifold3d's own CSG
            code = f"({code} {self.rng.choice(['+', '-', '^'])} {self._manifold_piece()})"
        return Part(code, foreign_reference("manifold", code), foreign="manifold")

    def _cross_section_piece(self):
        rng = self.rng
        if rng.random() < 0.5:
            make = f"m3d.CrossSection.square({text(rng.uniform(0.3, 1.2, 2))}, True)"
        else:
            make = f"m3d.CrossSection.circle({num(rng.uniform(0.2, 0.7))}, {rng.integers(6, 48)})"
        return f"{make}.rotate({num(rng.uniform(0, 360))}).translate({text(self.point(0.4))})"

    def leaf_cross_section(self):
        code = self._cross_section_piece()
        for _ in range(self.rng.integers(0, 3)):
            code = f"({code} {self.rng.choice(['+', '-', '^'])} {self._cross_section_piece()})"
        return Part(code, foreign_reference("cross_section", code), foreign="cross_section")

    def leaf_shapely(self):
        rng = self.rng
        c = self.point()
        code = (f"shapely.Point({num(c[0])}, {num(c[1])}).buffer({num(rng.uniform(0.3, 0.8))}, "
                f"quad_segs={rng.integers(2, 16)})")
        other = self.point()
        if rng.random() < 0.5:
            code += (f".difference(shapely.box({num(other[0])}, {num(other[1])}, "
                     f"{num(other[0] + 0.5)}, {num(other[1] + 0.3)}))")
        else:
            code += f".union(shapely.Point({num(other[0])}, {num(other[1])}).buffer({num(rng.uniform(0.1, 0.4))}))"
        return Part(code, foreign_reference("shapely", code), foreign="shapely")

    def _star(self, center, low, high, count):
        """A ring star-shaped about ``center``, radii in [low, high]; it holds the disc of radius
        ``low * cos(largest half gap)``, which the next ring inside stays within."""
        gaps = self.rng.uniform(0.6, 1.4, count)
        angles = np.cumsum(gaps / gaps.sum() * 2 * np.pi)
        radii = self.rng.uniform(low, high, count)
        ring = center + radii[:, None] * np.column_stack([np.cos(angles), np.sin(angles)])
        return ring, low * np.cos(np.max(gaps / gaps.sum()) * np.pi)

    def leaf_polygon(self):
        c = self.point(0.3)
        outer, room = self._star(c, 0.5, 1.0, self.rng.integers(3, 24))
        rings = [outer]
        for _ in range(self.rng.integers(0, 3)):  # a hole, then an island in it
            ring, room = self._star(c, 0.5 * room, 0.9 * room, self.rng.integers(3, 16))
            rings.append(ring)
        if len(rings) <= 2 and self.rng.random() < 0.7:
            code = f"nd.Polygon({text(outer)}, holes=[{', '.join(text(r) for r in rings[1:])}])"
        else:
            code = f"nd.Polygon.from_rings([{', '.join(text(r) for r in rings)}])"
        return Part(code, ref.even_odd(rings))

    # ------------------------------------------------------------------ extra leaves
    def extra_plugin(self, rng) -> Part:
        """A user's plug-in: the exact distance of a ball or a box, as a ScalarFunction (every
        backend) or a Function of a NumPy lambda (the NumPy backend), bounds a little loose or
        tight, the exactness promised or not."""
        d = self.dim
        if rng.random() < 0.5:
            c, r = rng.uniform(-0.5, 0.5, d), rng.uniform(0.3, 0.9)
            lower, upper = c - r, c + r
            params, reference, name = [*c, r], ref.ball(c, r), "ball"
            numpy_form = f"lambda p: np.sqrt(((p - np.array({text(c)})) ** 2).sum(axis=1)) - {num(r)}"
        else:
            c = rng.uniform(-0.5, 0.5, d)
            lower, upper = c - rng.uniform(0.2, 0.8, d), c + rng.uniform(0.2, 0.8, d)
            params, reference, name = [*lower, *upper], ref.box(lower, upper), "box"
            gap = f"np.maximum(np.array({text(lower)}) - p, p - np.array({text(upper)}))"
            numpy_form = (f"lambda p: (lambda g: np.where(g.max(axis=1) > 0, np.sqrt((np.maximum(g, 0.0) ** 2)"
                          f".sum(axis=1)), g.max(axis=1)))({gap})")
        pad = rng.uniform(0.0, 0.2) if rng.random() < 0.5 else 0.0
        bounds = text([lower - pad, upper + pad])
        exact = "True" if rng.random() < 0.7 else "False"
        flags = f"exact_inside={exact}, exact_outside={exact}"
        if rng.random() < 0.6:
            code = f"nd.ScalarFunction(plugins.{name}, {d}, {bounds}, params={text(params)}, {flags})"
            return Part(code, reference, frozenset({"scalar_plugin"}))
        return Part(f"nd.Function({numpy_form}, {d}, {bounds}, {flags})", reference, frozenset({"plugin"}))

    def extra_open_mesh(self, rng) -> Part:
        """A closed trimesh primitive less 1-3 triangles that share no vertex, loaded with
        ``holes="cap"``: each hole's rim is the removed triangle, so its cap (a fan to a point of
        its plane inside it) lies where the triangle was, and the reference is libigl's winding
        number of the primitive's own triangles, the removed ones included."""
        primitive = self._trimesh_primitive(rng)
        mesh = build(primitive)
        count, removed, used = rng.integers(1, 4), [], set()
        for face in rng.permutation(len(mesh.faces)):
            corners = set(mesh.faces[face].tolist())
            if not corners & used:
                removed.append(int(face))
                used |= corners
            if len(removed) == count:
                break
        code = (f"(lambda m: nd.TriangleMesh(m.vertices, np.delete(m.faces, {sorted(removed)}, axis=0), "
                f"holes='cap'))({primitive})")
        return Part(code, ref.capped_mesh(mesh.vertices, mesh.faces, sorted(removed)), frozenset({"open_mesh"}))

    # ------------------------------------------------------------------ nodes
    def _pair(self, a: Part, b: Part, operator: str, native: dict):
        """``a <op> b``, or the Part that one other library made of them: two objects of one
        library are combined by it (its ``native`` operator), a trimesh mesh on the left becomes
        ndpack's, other mixes of libraries take a fresh ndpack shape on the right (neither library
        knows the other), and a shapely geometry never stays on the left of an ndpack shape
        (shapely's operators raise a TypeError rather than defer to ndpack's)."""
        if a.foreign and b.foreign:
            if a.foreign == b.foreign and a.foreign in native:
                code = native[a.foreign](a.code, b.code)
                kinds = a.kinds | b.kinds
                return Part(code, foreign_reference(a.foreign, code), kinds, a.foreign)
            if a.foreign == "trimesh":
                a = Part(f"nd.TriangleMesh.from_trimesh({a.code})", a.reference, a.kinds)
            else:
                b = self.leaf_native()
        if a.foreign == "shapely" and not b.foreign:  # shapely's operators raise on other objects
            if operator == "-":
                a = self.leaf_native()
            else:
                a, b = b, a
        return a, b

    def leaf_native(self):
        """An ndpack primitive (no other library's object)."""
        return self.leaf_box() if self.rng.random() < 0.5 else self.leaf_ball()

    def _binary(self, a, b, operator, classname, combine, native, kind):
        paired = self._pair(a, b, operator, native)
        if isinstance(paired, Part):
            return Part(paired.code, paired.reference, paired.kinds | {kind}, paired.foreign)
        a, b = paired
        if not (a.foreign or b.foreign) and self.rng.random() < 0.3:
            code = f"nd.{classname}({a.code}, {b.code})"
        else:
            code = f"({a.code} {operator} {b.code})"
        return Part(code, combine(a.reference, b.reference), a.kinds | b.kinds | {kind})

    def node_union(self, depth):
        native = {"manifold": lambda a, b: f"({a} + {b})", "cross_section": lambda a, b: f"({a} + {b})",
                  "shapely": lambda a, b: f"{a}.union({b})", "trimesh": None}
        native = {k: v for k, v in native.items() if v}
        return self._binary(self.tree(depth), self.tree(depth), "|", "Union", ref.union, native, "union")

    def node_union_n(self, depth):
        parts = [self.tree(depth) for _ in range(3)]
        parts = [p if not p.foreign else self.leaf_native() for p in parts]
        joined = ", ".join(p.code for p in parts)
        code = f"nd.Union({joined})" if self.rng.random() < 0.5 else "(" + " | ".join(p.code for p in parts) + ")"
        return Part(code, ref.union(*[p.reference for p in parts]),
                    frozenset().union(*[p.kinds for p in parts]) | {"union"})

    def node_intersection(self, depth):
        native = {"manifold": lambda a, b: f"({a} ^ {b})", "cross_section": lambda a, b: f"({a} ^ {b})",
                  "shapely": lambda a, b: f"{a}.intersection({b})"}
        return self._binary(self.tree(depth), self.tree(depth), "&", "Intersection", ref.intersection, native,
                            "intersection")

    def node_difference(self, depth):
        native = {"manifold": lambda a, b: f"({a} - {b})", "cross_section": lambda a, b: f"({a} - {b})",
                  "shapely": lambda a, b: f"{a}.difference({b})"}
        return self._binary(self.tree(depth), self.tree(depth), "-", "Difference", ref.difference, native,
                            "difference")

    def node_cut(self, depth):
        a = self.tree(depth)
        cut = self.cutter(a.reference)
        keep = self.rng.random() < 0.6
        if a.foreign == "shapely":  # the ndpack shape on the left: a - cut is ~cut & a
            code = f"({cut.code} & {a.code})" if keep else f"(~{cut.code} & {a.code})"
        else:
            code = f"({a.code} & {cut.code})" if keep else f"({a.code} - {cut.code})"
        if keep:
            reference = ref.intersection(a.reference, cut.reference)
        else:
            reference = ref.difference(a.reference, cut.reference)
        return Part(code, reference, a.kinds | cut.kinds | {"cut"})

    def node_complement(self, depth):
        a, b = self.tree(depth), self.tree(depth)
        if b.foreign:  # only ndpack shapes have a complement
            b = self.leaf_native()
        inverse = f"~{b.code}" if self.rng.random() < 0.5 else f"nd.Complement({b.code})"
        if a.foreign:
            code = f"({inverse} & {a.code})"
        else:
            code = f"({a.code} & {inverse})"
        return Part(code, ref.intersection(a.reference, ref.complement(b.reference)),
                    a.kinds | b.kinds | {"complement"})

    def node_smooth_union(self, depth):
        a, b = self.exact(depth), self.exact(depth)
        blend = self.rng.uniform(0.05, 0.4)
        if self.rng.random() < 0.5:
            code = f"{a.code}.smooth_union({b.code}, {num(blend)})"
        else:
            code = f"nd.SmoothUnion({a.code}, {b.code}, {num(blend)})"
        return Part(code, ref.smooth_union(a.reference, b.reference, blend), a.kinds | b.kinds | {"smooth_union"})

    def node_offset(self, depth):
        a = self.exact(depth)
        size = float(np.ptp(a.reference.box, axis=0).min())
        amount = self.rng.uniform(-0.3, 0.3) * size
        code = f"{a.code}.offset({num(amount)})" if self.rng.random() < 0.5 else f"nd.Offset({a.code}, {num(amount)})"
        return Part(code, ref.offset(a.reference, amount), a.kinds | {"offset"})

    def node_shell(self, depth):
        a = self.exact(depth)
        thickness = self.rng.uniform(0.05, 0.3)
        code = (f"{a.code}.shell({num(thickness)})" if self.rng.random() < 0.5
                else f"nd.Shell({a.code}, {num(thickness)})")
        return Part(code, ref.shell(a.reference, thickness), a.kinds | {"shell"})

    def _affine(self, part: Part, matrix, center, kind, shift=0.0) -> Part:
        """Another library's object moved by its own library: ``x -> matrix (x - center) + center + shift``."""
        shift = center - matrix @ center + shift
        if part.foreign in ("manifold", "cross_section"):
            code = f"{part.code}.transform({text(np.column_stack([matrix, shift]))})"
        else:
            (a, b), (d, e) = matrix
            code = f"shapely.affinity.affine_transform({part.code}, {text([a, b, d, e, *shift])})"
        return Part(code, foreign_reference(part.foreign, code), part.kinds | {kind}, part.foreign)

    def _ndpack(self, part: Part) -> Part:
        if part.foreign == "trimesh":
            return Part(f"nd.TriangleMesh.from_trimesh({part.code})", part.reference, part.kinds)
        return part

    def node_translate(self, depth, part=None):
        part = self.tree(depth) if part is None else part
        shift = self.point(0.5)
        if part.foreign and part.foreign != "trimesh":
            return self._affine_shift(part, shift)
        part = self._ndpack(part)
        code = (f"{part.code}.translate({text(shift)})" if self.rng.random() < 0.5
                else f"nd.Translate({part.code}, {text(shift)})")
        return Part(code, ref.translated(part.reference, shift), part.kinds | {"translate"})

    def _affine_shift(self, part, shift):
        """Another library's object moved by ``shift``."""
        return self._affine(part, np.eye(self.dim), np.zeros(self.dim), "translate", shift)

    def node_rotate(self, depth, part=None):
        part = self.tree(depth) if part is None else part
        matrix = orthogonal(self.rng, self.dim, reflect=self.rng.random() < 0.2)
        center = self.point(0.5)
        return self._linear(part, matrix, center, "rotate", "rotate", "Rotate", text(matrix),
                            lambda reference: ref.rotated(reference, matrix, center))

    def node_scale(self, depth, part=None):
        part = self.tree(depth) if part is None else part
        factor, center = float(np.exp(self.rng.uniform(-0.7, 0.7))), self.point(0.5)
        return self._linear(part, factor * np.eye(self.dim), center, "scale", "scale_by", "Scale", num(factor),
                            lambda reference: ref.scaled(reference, factor, center))

    def _linear(self, part, matrix, center, kind, method, node, argument, mapped):
        """``part`` mapped by ``matrix`` about ``center``: another library's object through
        :meth:`_affine`, else as ndpack's ``method`` or ``node`` class (half each) with ``argument``
        (code), its reference mapped by ``mapped``."""
        if part.foreign and part.foreign != "trimesh":
            return self._affine(part, matrix, center, kind)
        part = self._ndpack(part)
        if self.rng.random() < 0.5:
            code = f"{part.code}.{method}({argument}, center={text(center)})"
        else:
            code = f"nd.{node}({part.code}, {argument}, {text(center)})"
        return Part(code, mapped(part.reference), part.kinds | {kind})

    def far_away(self, part: Part) -> Part:
        """The whole tree scaled by up to 100 either way and moved up to 1,000 away: float64 at
        other scales than the unit's."""
        factor = float(10 ** self.rng.uniform(-2, 2))
        shift = self.unit() * 10 ** self.rng.uniform(0, 3)
        if part.foreign and part.foreign != "trimesh":
            moved = self._affine(part, factor * np.eye(self.dim), np.zeros(self.dim), "scale")
            return self._affine_shift(moved, shift)
        part = self._ndpack(part)
        code = f"{part.code}.scale_by({num(factor)}).translate({text(shift)})"
        reference = ref.translated(ref.scaled(part.reference, factor, np.zeros(self.dim)), shift)
        return Part(code, reference, part.kinds | {"far_away"})


def case(seed: int, index: int, max_depth: int = 3, extended: bool = True) -> Case:
    """Case ``index`` of the run ``seed``: a tree and its packing parameters, the same every time.
    ``extended=False`` draws no extra leaf (plug-ins, open meshes): the trees as before them."""
    rng = np.random.default_rng([seed, index])
    dims = list(DIMENSIONS)
    dim = int(rng.choice(dims, p=[DIMENSIONS[d] for d in dims]))
    drawer = Drawer(rng, dim, np.random.default_rng([seed, index, 1]) if extended else None)
    part = drawer.tree(int(rng.integers(1, max_depth + 1)))
    if rng.random() < 0.15:
        part = drawer.far_away(part)
    grids = GRIDS[dim]
    grid = grids[rng.integers(len(grids))]
    return Case(seed, index, part.code, part.reference, sorted(part.kinds), int(rng.integers(8, 41)),
                None if grid is None else int(grid), int(rng.integers(0, 2**31)))
