"""Sphere-trees: levels of spheres, each node holding its children's part of the shape.

Collision and proximity queries descend a hierarchy: a coarse sphere is tested first, and its
children only where it is hit. Two kinds are built here:

- :func:`covering_tree`: every level covers the whole shape (the root is one sphere around it);
  a node's children are a covering, by at most ``branching`` spheres, of the samples it serves,
  made like :func:`ndpack.cover` with a count. Then each node grows to hold every sample of the
  shape that lies in its children (bottom up), so a query that misses a node misses its children
  there too. For robots and games: the deepest level is the collision model, the others cull.
- :func:`inner_tree`: an Inner Sphere Tree (Weller and Zachmann) over a packing: the leaves are
  the packed spheres, split into balanced groups along the widest axis, and each node is a sphere
  enclosing its children's spheres.

Trees save as the sphere-tree toolkit's ``.sph`` (Bradshaw and O'Sullivan), with all levels, and
:meth:`SphereTree.level` gives one level's spheres for cuRobo or URDF files.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from ...errors import DimensionError, ParameterError
from ...geometry import ball_union
from ...oracle import check_packable
from ...shapes.adapters import as_oracle
from .boundary import sample_cells
from .boundary import samples as shape_samples
from .set_cover import FIX_LARGEST, FIX_LARGEST_SHARE, Problem, _protrusions

#: Fresh sample sets drawn to close a covering tree's gaps between samples, at most.
TREE_PASSES = 8


@dataclass
class SphereTree:
    """Levels of spheres, the root level first.

    Attributes
    ----------
    centers : list of (k_l, d) float64
        Level ``l``'s centres; level 0 holds the root.
    radii : list of (k_l,) float64
    parents : list of (k_l,) int64
        Each node's parent in the level above (-1 for the root).
    branching : int
        The most children of a node.
    kind : {"covering", "inner"}
    protrusion : list of float
        Per level, the most a sphere reaches outside the shape (covering trees; NaN for inner).
    """

    centers: list
    radii: list
    parents: list
    branching: int
    kind: str
    protrusion: list = field(default_factory=list)
    shape: object = field(default=None, repr=False, compare=False)

    @property
    def depth(self) -> int:
        """Levels, the root's included."""
        return len(self.radii)

    @property
    def dim(self) -> int:
        return self.centers[0].shape[1]

    def level(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """One level's spheres (default order: as built); ``-1`` is the leaves. (centers, radii)."""
        return self.centers[index], self.radii[index]

    def children(self, index: int, node: int) -> np.ndarray:
        """The nodes of level ``index + 1`` whose parent is ``node`` of level ``index``."""
        return np.flatnonzero(self.parents[index + 1] == node)

    def __repr__(self) -> str:
        sizes = " + ".join(str(len(r)) for r in self.radii)
        return f"<SphereTree {self.kind}, branching {self.branching}, {self.depth} levels ({sizes} spheres)>"

    def check(self, shape=None, samples: int = 20_000, seed: int = 2) -> dict:
        """How well the tree nests, on fresh samples of the shape (float64).

        Returns a dict: ``nested``, the samples lying in a child but outside its parent (0 for a
        sound tree); for covering trees also ``uncovered``, per level the samples outside the
        level's union; for inner trees ``enclosed``, the children not inside their parent.
        """
        if self.kind == "inner":
            outside = 0
            for level in range(1, self.depth):
                parent = self.parents[level]
                offsets = self.centers[level] - self.centers[level - 1][parent]
                reach = np.linalg.norm(offsets, axis=1) + self.radii[level]
                outside += int(np.count_nonzero(reach > self.radii[level - 1][parent] * (1 + 1e-12) + 1e-300))
            return {"enclosed": outside == 0, "not_enclosed": outside}
        shape = self.shape if shape is None else shape
        rng = np.random.default_rng(seed)
        points, _ = shape_samples(shape, samples, rng, sample_cells(shape))
        uncovered = [int(np.count_nonzero(ball_union.gaps(points, c, r) > 1e-9 * shape.scale))
                     for c, r in zip(self.centers, self.radii)]
        return {"uncovered": uncovered, "nested": _nest(self, points)}

    def save(self, path) -> Path:
        """Write the sphere-tree toolkit's ``.sph``: ``levels branching``, then a line ``x y z r 1`` per
        slot, level by level, node ``i``'s children in slots ``i * branching + 1 ...``; unused
        slots have radius 0. 3-D only; read back a level with :func:`ndpack.io.read_sph`."""
        if self.dim != 3:
            raise DimensionError(f"the .sph format holds 3-D trees; this one is {self.dim}-D")
        path = Path(path)
        b = self.branching
        slots = [np.zeros(1, dtype=np.int64)]  # each node's slot within its level
        for level in range(1, self.depth):
            parent_slot = slots[-1][self.parents[level]]
            rank = np.zeros(len(self.parents[level]), dtype=np.int64)
            seen: dict[int, int] = {}
            for i, parent in enumerate(self.parents[level].tolist()):
                rank[i] = seen.get(parent, 0)
                seen[parent] = rank[i] + 1
            slots.append(parent_slot * b + rank)
        rows = []
        for level in range(self.depth):
            table = np.zeros((b**level, 5))
            table[slots[level], :3] = self.centers[level]
            table[slots[level], 3] = self.radii[level]
            table[:, 4] = 1
            rows.append(table)
        np.savetxt(path, np.vstack(rows), fmt=["%.17g"] * 4 + ["%d"], header=f"{self.depth} {b}", comments="")
        return path


# ------------------------------------------------------------------------------------------------ inner trees
def inner_tree(packing, branching: int = 8) -> SphereTree:
    """An Inner Sphere Tree over a packing's spheres (any dimension).

    The spheres are split into at most ``branching`` groups of balanced size along the widest
    axis, recursively, so the tree has ``ceil(log_b n) + 1`` levels; each node is a sphere
    enclosing its children's (:func:`ndpack.geometry.ball_union.enclosing_sphere`). Nodes with one child
    are that child.

    Parameters
    ----------
    packing : Packing
    branching : int
        At least 2.
    """
    _check_branching(branching)
    centers, radii = np.asarray(packing.centers, dtype=np.float64), np.asarray(packing.radii, dtype=np.float64)
    if not len(radii):
        raise ParameterError("the packing has no spheres to build a tree on")
    depth = 1
    while branching ** (depth - 1) < len(radii):
        depth += 1
    # Top down: the groups of leaf ids at every level.
    groups = [[np.arange(len(radii))]]
    for level in range(1, depth):
        groups.append([part for group in groups[-1] for part in _kd_parts(centers, group, min(branching, len(group)))])
    parents = [np.full(1, -1, dtype=np.int64)]
    for level in range(1, depth):
        owner = {int(leaf): i for i, group in enumerate(groups[level - 1]) for leaf in group}
        parents.append(np.array([owner[int(g[0])] for g in groups[level]], dtype=np.int64))
    # Bottom up: each node encloses its children's spheres (so, in turn, every leaf below it).
    order = np.concatenate(groups[-1])
    tree_centers, tree_radii = [centers[order]], [radii[order]]
    for level in range(depth - 2, -1, -1):
        below_c, below_r, below_parent = tree_centers[0], tree_radii[0], parents[level + 1]
        spheres = [ball_union.enclosing_sphere(below_c[below_parent == node], below_r[below_parent == node])
                   for node in range(len(groups[level]))]
        tree_centers.insert(0, np.array([sphere[0] for sphere in spheres]))
        tree_radii.insert(0, np.array([sphere[1] for sphere in spheres]))
    return SphereTree(tree_centers, tree_radii, parents, branching, "inner", [float("nan")] * depth)


def _kd_parts(centers, ids, parts):
    """Split ``ids`` into ``parts`` groups of balanced size along the widest axis, recursively
    halving the number of groups (a k-d split): a group of at most ``parts * m`` gives groups of
    at most ``m``."""
    if parts == 1 or len(ids) <= 1:
        return [ids]
    points = centers[ids]
    axis = int(np.argmax(np.ptp(points, axis=0)))
    order = ids[np.argsort(points[:, axis], kind="stable")]
    left_parts = parts // 2
    cut = int(round(len(ids) * left_parts / parts))
    return _kd_parts(centers, order[:cut], left_parts) + _kd_parts(centers, order[cut:], parts - left_parts)


# ------------------------------------------------------------------------------------------------ covering trees
def covering_tree(shape, branching: int = 8, depth: int = 3, *, samples: int = 20_000, packing=None, seed: int = 0,
                  backend=None, device=None) -> SphereTree:
    """A sphere-tree whose every level covers ``shape``; level ``l`` has at most ``branching ** l``
    spheres.

    Parameters
    ----------
    shape : Oracle
    branching : int
        Children per node, at least 2 (8 is the sphere-tree toolkit's usual).
    depth : int
        Levels, the root's included (3: 1 + 8 + 64 spheres at most for branching 8).
    samples, packing, seed, backend, device :
        As for :func:`ndpack.cover`.

    Returns
    -------
    SphereTree
        Its ``protrusion`` lists each level's largest ``r + f(c)``.
    """
    _check_branching(branching)
    if isinstance(depth, bool) or not isinstance(depth, (int, np.integer)) or depth < 1:
        raise ParameterError(f"depth must be a positive integer, got {depth!r}")
    shape = as_oracle(shape)
    check_packable(shape)
    problem = Problem.make(shape, samples, packing, seed, backend, device, compiled=True)
    regions = [np.arange(len(problem.points))]
    centers, radii, clearances, parents = [], [], [], []
    for level in range(depth):
        width = 1 if level == 0 else branching
        level_centers, level_radii, level_clearance, level_parents, next_regions = [], [], [], [], []
        for node, ids in enumerate(regions):
            if not len(ids):
                continue
            c, r, d, _ = problem.cover_count(ids, width)
            _, owner, _, _ = ball_union.best_balls(problem.points[ids], c, r, d)
            for child in range(len(r)):
                next_regions.append(ids[owner == child])
            level_centers.append(c)
            level_radii.append(r)
            level_clearance.append(d)
            level_parents.append(np.full(len(r), node if level else -1, dtype=np.int64))
        centers.append(np.vstack(level_centers))
        radii.append(np.concatenate(level_radii))
        clearances.append(np.concatenate(level_clearance))
        parents.append(np.concatenate(level_parents))
        regions = next_regions
    tree = SphereTree(centers, radii, parents, int(branching), "covering", shape=shape)
    _nest(tree, problem.points, 0.5 * problem.spacing)
    clean = 0
    for attempt in range(TREE_PASSES):  # fresh sets, ever larger, until two in a row need nothing
        fresh, _ = problem.fresh(min(samples * 2 ** (attempt + 1), FIX_LARGEST, FIX_LARGEST_SHARE * samples))
        grown = False
        for level in range(depth):
            gap, _, cheapest, _ = ball_union.best_balls(fresh, centers[level], radii[level], clearances[level])
            missed = gap > 0
            if missed.any():
                grown = True
                lengths = np.linalg.norm(fresh[missed] - centers[level][cheapest[missed]], axis=1)
                np.maximum.at(radii[level], cheapest[missed], lengths + 0.5 * problem.spacing)
        grown |= _nest(tree, fresh, 0.5 * problem.spacing) > 0
        clean = 0 if grown else clean + 1
        if clean == 2:
            break
    tree.protrusion = [float(_protrusions(shape, c, r).max(initial=0.0)) for c, r in zip(centers, radii)]
    return tree


def _nest(tree: SphereTree, points, slack: float | None = None) -> int:
    """Count the ``points`` that lie in a child but outside its parent, over all nodes; with a
    ``slack``, first grow each such parent to hold them plus ``slack`` (bottom up, so that growth
    reaches the root). Returns the count."""
    count = 0
    for level in range(tree.depth - 1, 0, -1):
        holders = cKDTree(points).query_ball_point(tree.centers[level], tree.radii[level], return_sorted=False)
        for child, held in enumerate(holders):
            if not held:
                continue
            parent = tree.parents[level][child]
            reach = np.linalg.norm(points[held] - tree.centers[level - 1][parent], axis=1)
            outside = int(np.count_nonzero(reach > tree.radii[level - 1][parent]))
            count += outside
            if outside and slack is not None:
                tree.radii[level - 1][parent] = float(reach.max()) + slack
    return count


def _check_branching(branching):
    if isinstance(branching, bool) or not isinstance(branching, (int, np.integer)) or branching < 2:
        raise ParameterError(f"branching must be an integer of at least 2, got {branching!r}")
