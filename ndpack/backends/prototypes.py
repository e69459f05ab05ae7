"""The driver's prototypes, held where the backend computes: host memory, or a GPU's.

The ProtoSphere driver keeps one prototype per grid cell: a point, its clearance, and whether it
has been polished. Each round touches only a few of them (the leaders, and those a new sphere
touched), so the driver speaks to the whole set through :class:`Prototypes`, by ids: it asks
for the largest clearances, the prototypes a new sphere touched, or for some ids to move, and
gets back small host arrays. A GPU backend keeps the full set on its device
(:class:`DevicePrototypes`), so no round copies all prototypes to the host and back; the CPU
backends use :class:`HostPrototypes`, which calls the backend's array operations.

Ids are int64 prototype indices, ascending unless said otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .sphere_index import DeviceIndex

#: :meth:`DevicePrototypes.leaders` asks for the prototypes within a window (this fraction) below
#: the largest clearance, widened by ``WIDEN`` until it holds the leaders and those near them, and
#: narrowed again (not below the polish window) when it held far more.
FIRST_WINDOW, WIDEN = 0.05, 4.0
#: On a GPU, a move launch of few prototypes lasts as long as its slowest warp, and the 32 lanes of
#: a warp walk the mesh's tree on divergent paths: each step waits for the longest of 32 walks,
#: both branches of every fork taken in turn. A launch of few prototypes therefore gives each
#: prototype up to ``SPREAD_MAX`` threads, of which the first moves it and the rest idle, in at
#: most ``SPREAD_THREADS`` threads (a power of two; see :func:`lane_spread`).
SPREAD_MAX, SPREAD_THREADS = 32, 1 << 15


@dataclass(frozen=True)
class PolishAhead:
    """A polish that rides on a move (:meth:`Prototypes.move`): the moved prototypes whose new
    clearance reaches ``low`` continue with the polish schedule ``steps`` (T,), and the prototypes
    ``ids`` (k,), none of them moved, are polished. On a GPU it is the same launch, which costs
    its longest prototype's walk however few it moves."""

    steps: np.ndarray
    low: float
    ids: np.ndarray

    def later(self) -> PolishAhead:
        """The same polish for the moves after the first, which polished ``ids`` already."""
        return replace(self, ids=self.ids[:0])


def no_wall(count: int) -> np.ndarray:
    """(count,) walls that never spare a distance evaluation (see
    :meth:`ndpack.backends.base.Backend.converge`)."""
    return np.full(count, -np.inf)


def lane_spread(count: int, most: int = SPREAD_MAX, threads: int | None = None) -> int:
    """Threads per prototype of a move launch of ``count`` prototypes: the largest power of two
    up to ``most`` that keeps the launch within ``threads`` threads (default ``SPREAD_THREADS``),
    at least 1."""
    threads = SPREAD_THREADS if threads is None else threads
    spread = 1
    while 2 * spread <= most and 2 * spread * count <= threads:
        spread *= 2
    return spread


def best_starts(backend, shape, candidates, centers, radii, neighbours):
    """Per prototype, the candidate with the largest clearance (the first of equals).

    Parameters
    ----------
    candidates : (t, k, d) float64
        ``t`` starting points for each of ``k`` prototypes.
    centers, radii, neighbours :
        The spheres and each prototype's (k, w) neighbour table, as in :meth:`Backend.clearance`.

    Returns
    -------
    points : (k, d) float64 and clearance : (k,) float64
    """
    tries, count, dim = candidates.shape
    clearance = backend.clearance(
        shape, candidates.reshape(-1, dim), centers, radii, np.tile(neighbours, (tries, 1))
    ).reshape(tries, count)
    best, rows = np.argmax(clearance, axis=0), np.arange(count)
    return candidates[best, rows], clearance[best, rows]


def converge_by_move(backend, device, shape, points, cell_lower, cell_upper, centers, radii, neighbours, steps,
                     wall=None, starts=None):
    """:meth:`~ndpack.backends.base.Backend.converge` of a GPU backend, run by the store's move kernel
    (``move_ids``: each point its own cell and neighbour row, no restarts, no polish) with
    :meth:`DevicePrototypes.move`'s argument types, so that the move kernel, the longest to compile,
    serves both and no converge kernel compiles (a converge kernel was 5.5 s of a fresh H100's first
    compile of a mesh on numba-cuda, ``bench/cuda_compile.py --on-gpu``). Each point starts from the
    best of it and ``starts`` by clearance, the first of equals, as numba's ``best_start`` chooses.
    At most the backend's ``cooperative_converge_most`` points walk a mesh's tree a block of lanes
    each (see :mod:`ndpack.backends.warp_lanes`).

    ``device`` is the backend's device adapter for ``shape`` (as :class:`DevicePrototypes` takes);
    the other arguments and the result are :meth:`~ndpack.backends.base.Backend.converge`'s: points
    (k, d) float64 and clearance (k,) float64.
    """
    points = backend._best_of_starts(shape, points, starts, centers, radii, neighbours)
    count = len(points)
    if count == 0:
        return np.zeros((0, shape.dim)), np.zeros(0)
    wall = no_wall(count) if wall is None else wall
    table = neighbours if neighbours.shape[1] else np.full((count, 1), len(centers))  # a padded row each
    d_centers, d_radii = device.spheres(centers, radii)
    d_points, d_clearance, d_steps = device.upload(points, "point"), device.empty(count, "float"), device.upload(
        steps, "float")
    most = backend.cooperative_converge_most
    lanes = SPREAD_MAX if count <= most else 1
    device.launch("move_ids", lanes * count, device.upload(np.arange(count), "index"), device.empty(1, "point"), 0, 0,
                  np.uint64(0), d_points, d_clearance, device.empty(count, "index"), device.upload(cell_lower, "point"),
                  device.upload(cell_upper, "point"), device.upload(wall, "float"), device.params, d_centers, d_radii,
                  device.upload(table, "index"), d_steps, device.h, 0, lanes, d_steps, float(np.inf), count,
                  lanes=lanes, most=most)
    return tuple(device.fetch((d_points, count), (d_clearance, count)))


def top_order(ids: np.ndarray, clearance: np.ndarray, k: int) -> np.ndarray:
    """Positions (k,) of the ``k`` largest clearances, largest first and ties by lower id.

    The tie rule makes every backend choose the same prototype among equal clearances, which
    symmetric shapes produce. Where ``k`` is a small part of them, only those at least the
    ``k``-th largest are sorted (after a partition, linear in their number).
    """
    count = len(clearance)
    if k <= 0:
        return np.empty(0, dtype=np.int64)
    if k < count // 2:
        some = largest(clearance, k)
        return some[np.lexsort((ids[some], -clearance[some]))[:k]]
    return np.lexsort((ids, -clearance))[:k]


def largest(values: np.ndarray, most: int | None) -> np.ndarray:
    """Positions (j,) ascending of the ``most`` largest of ``values`` (k,) and of any equal to the
    last of them; all where ``most`` is None or ``k <= most``."""
    count = len(values)
    if most is None or count <= most:
        return np.arange(count)
    if most <= 0:
        return np.empty(0, dtype=np.int64)
    return np.flatnonzero(values >= np.partition(values, count - most)[count - most])


def cell_bounds(lower, upper, distance, wall_slack):
    """For cells ``lower``, ``upper`` (k, d): their centres (k, d), an upper bound of any clearance
    inside each (the reach, which finds the spheres near the cell) (k,), and a lower bound of the
    boundary's distance at each centre less ``wall_slack`` for rounding (the wall) (k,); both from
    the centre's signed distance, ``distance(centres) -> (k,)``, which is 1-Lipschitz. The device
    kernels ``split_cut`` and ``cell_distances`` compute the same."""
    centers = 0.5 * (lower + upper)
    centre_distance = distance(centers)
    half_diagonal = 0.5 * np.linalg.norm(upper - lower, axis=1)
    return centers, -centre_distance + half_diagonal, -centre_distance - wall_slack


class Prototypes:
    """All prototypes of one packing run, with their grid cells.

    Parameters
    ----------
    cell_lower, cell_upper : (n, d) float64
        The box of each prototype's grid cell, which confines it.
    reach : (n,) float64
        Upper bound of the clearance of any point in each cell (finds the spheres near it).
    points : (n, d) float64 and clearance : (n,) float64
        Starting positions and their clearances.
    wall : (n,) float64, optional
        Lower bound of the boundary's distance at each cell's centre (see
        :meth:`~ndpack.backends.base.Backend.converge`); None evaluates the shape everywhere.

    Where the arrays live, and how the cells split, belongs to the subclass.
    """

    def __init__(self, cell_lower, cell_upper, reach, points, clearance, wall=None):
        self.dim = cell_lower.shape[1]

    def __len__(self) -> int:
        raise NotImplementedError

    def select(self, low=-np.inf, high=np.inf, unpolished=False):
        """Ids of the prototypes with ``low <= clearance <= high`` (and not polished, if asked),
        and their clearances: ((m,) int64, (m,) float64)."""
        raise NotImplementedError

    def top(self, below=np.inf) -> float:
        """The largest clearance below ``below``; -inf where none is."""
        raise NotImplementedError

    def candidates(self, low, most=None):
        """The prototypes with clearance ``>= low``, with what a round needs to choose among them:
        ids (m,) int64 ascending, clearances (m,) float64, points (m, d) float64 and whether each
        is polished (m,) bool. With ``most``, only those of the ``most`` largest clearances and
        any equal to the last of them (:func:`largest`): a round takes no more, from a store
        that holds 5 million prototypes at a million spheres of the armadillo."""
        raise NotImplementedError

    def window(self, fraction: float, most=None, late=None):
        """The largest clearance and the prototypes within ``fraction`` below it, as
        :meth:`candidates` gives them (with ``low = (1 - fraction)`` times it, and ``most``), in
        one query: ids, clearances, points, polish flags, the largest clearance (a float) and the
        frontier the window was taken below (a float). None are given when the largest is not
        positive.

        ``late = (floor, few)``, the fast mode's late finds (:meth:`~ndpack.drivers.greedy.rounds.Fast.choose`):
        where the largest clearance is at least ``floor`` and fewer than ``few`` prototypes lie
        within the window below it, the frontier is the largest clearance below that window
        (where it is positive), and the window is taken below it.
        """
        raise NotImplementedError

    def leaders(self, k: int, window: float):
        """The ``k`` largest clearances (fewer if n < k), largest first, and the unpolished near them.

        Returns
        -------
        ids : (k,) int64, clearance : (k,) float64, points : (k, d) float64
            The leaders, ties in clearance by lower id (:func:`top_order`).
        unpolished : (m,) int64
            Ids of the unpolished prototypes with clearance ``>= (1 - window)`` times the k-th
            largest; empty when that is not positive.
        """
        raise NotImplementedError

    def touched(self, new_centers, new_radii):
        """The prototypes whose clearance ball meets one of the new spheres (k, d), (k,).

        Returns ids (t,) int64, their points (t, d) float64 and the nearest new sphere of each
        (t,) int64 (smallest gap, the first of equals; see :meth:`Backend.touched`).
        """
        raise NotImplementedError

    def gather(self, ids):
        """Points (k, d) and clearances (k,) of prototypes ``ids``, on the host."""
        raise NotImplementedError

    def move(self, ids, centers, radii, steps, restarts=None, polish=False, ahead=None):
        """Converge prototypes ``ids`` among the spheres ``centers`` (m, d), ``radii`` (m,).

        Each starts from the best (largest clearance) of its current point and the starts of
        ``restarts`` (a :class:`~ndpack.backends.restarts.Restarts`; its first points belong to
        the first ids), if given, and follows the cooling schedule ``steps`` (T,).
        ``polish=False``: the result replaces the prototype, which is marked unpolished (the
        spheres changed). ``polish=True``: it replaces it only where the clearance grew, and
        marks it polished. ``ahead`` (a :class:`PolishAhead`, with ``polish=False``): then the
        moved prototypes whose clearance reaches ``ahead.low``, and ``ahead.ids``, are polished.
        """
        raise NotImplementedError

    def all(self):
        """Every point (n, d) and clearance (n,) on the host: for results, not for rounds."""
        return self.gather(np.arange(len(self)))

    def lower_clearance(self, ids, values):
        """Lower the clearances of prototypes ``ids`` (k,) to at most ``values`` (k,): what a new
        sphere leaves of them at their points, before they move again."""
        raise NotImplementedError

    def tighten_reach(self, ids, centers, radii):
        """Tighten the reach of cells ``ids`` (k,) by the spheres ``centers`` (m, d), ``radii``
        (m,) (see :meth:`~ndpack.backends.base.Backend.near_spheres`), as a move would, without
        moving their prototypes: the fast mode splits again a level of cells before any of them
        converges."""
        raise NotImplementedError

    def split_candidates(self, low, longest, most=None):
        """The cells the fast mode may split: longer than ``longest`` on some side, and whose bound
        of the clearance anywhere inside reaches ``low``; with ``most``, only those of the ``most``
        largest bounds and any equal to the last of them (:func:`largest`).

        The bound is kept per cell and only tightens (clearances only shrink as spheres arrive):
        ``min(reach, clearance + the way from the prototype to the cell's farthest corner)``, the
        clearance being 1-Lipschitz; the reach alone for a prototype that has not converged yet
        (clearance -inf: a half made by :meth:`split_cells`).

        Returns ids (k,) int64 ascending and their bounds (k,) float64.
        """
        raise NotImplementedError

    def split_cells(self, ids, wall_slack):
        """Cut cells ``ids`` (k,) ascending in two across their longest side (the first of equal
        sides), at the middle. The half that holds the prototype keeps it (still a local maximum
        there); the other half gets a new prototype at its centre, with clearance -inf, not
        converged: ids ``len(self)`` on, in the order of ``ids``. Each half's reach and wall come
        from the shape's distance at its centre (:func:`cell_bounds`, the wall less
        ``wall_slack``), the reach no more than the cell's before.

        Returns the new prototypes' ids (k,) int64.
        """
        raise NotImplementedError

    def add_cells(self, cell_lower, cell_upper, reach, wall):
        """Cells ``cell_lower``, ``cell_upper`` (k, d), with their ``reach`` and ``wall`` (k,), each
        with a new prototype at its centre, not converged (clearance -inf, as
        :meth:`split_cells` makes them): ids ``len(self)`` on. The driver's final search adds the
        cells it set aside at the start (none of their starts lay inside).

        Returns the new prototypes' ids (k,) int64.
        """
        raise NotImplementedError


class HostPrototypes(Prototypes):
    """Prototypes in host memory; the heavy work runs through the backend's array operations.

    Every array is an attribute: ``cell_lower``, ``cell_upper`` (n, d), ``reach``, ``wall``,
    ``points`` (n, d), ``clearance``, ``polished`` (n,), and the fast mode's per-cell ``longest``
    side and split ``bound`` (n,), made at its first :meth:`split_candidates`.
    """

    def __init__(self, backend, shape, cell_lower, cell_upper, reach, points, clearance, wall=None):
        super().__init__(cell_lower, cell_upper, reach, points, clearance, wall)
        self.backend, self.shape = backend, shape
        self.cell_lower, self.cell_upper, self.reach = cell_lower, cell_upper, reach
        self.wall = no_wall(len(reach)) if wall is None else np.asarray(wall, dtype=np.float64)
        self.points, self.clearance = points, clearance
        self.polished = np.zeros(len(points), dtype=bool)
        self.longest = self.bound = None

    def __len__(self) -> int:
        return len(self.reach)

    def select(self, low=-np.inf, high=np.inf, unpolished=False):
        mask = (self.clearance >= low) & (self.clearance <= high)
        if unpolished:
            mask &= ~self.polished
        ids = np.flatnonzero(mask)
        return ids, self.clearance[ids]

    def top(self, below=np.inf):
        return float(np.max(self.clearance, where=self.clearance < below, initial=-np.inf))

    def candidates(self, low, most=None):
        return self._rows(np.flatnonzero(self.clearance >= low), most)

    def _rows(self, ids, most=None):
        """What :meth:`candidates` gives of prototypes ``ids`` (m,), ascending."""
        ids = ids[largest(self.clearance[ids], most)]
        return ids, self.clearance[ids], self.points[ids], self.polished[ids]

    def window(self, fraction, most=None, late=None):
        top = self.top()
        if not top > 0:
            return (*self.candidates(np.inf), top, top)
        frontier, ids = top, np.flatnonzero(self.clearance >= (1 - fraction) * top)
        if late is not None and top >= late[0] and len(ids) < late[1]:
            below = self.top(below=(1 - fraction) * top)
            if below > 0:
                frontier, ids = below, np.flatnonzero(self.clearance >= (1 - fraction) * below)
        return (*self._rows(ids, most), top, frontier)

    def leaders(self, k, window):
        k = min(k, len(self))
        if k == 1:  # argmax takes the first (lowest id) of equal maxima, as top_order does
            ids = np.array([int(np.argmax(self.clearance))])
            clearance = self.clearance[ids]
        else:
            kth = np.partition(self.clearance, len(self) - k)[len(self) - k]
            ids, clearance = self.select(low=kth)
            order = top_order(ids, clearance, k)
            ids, clearance = ids[order], clearance[order]
        kth = clearance[-1]
        unpolished = self.select(low=(1 - window) * kth, unpolished=True)[0] if kth > 0 else ids[:0]
        return ids, clearance, self.points[ids], unpolished

    def gather(self, ids):
        return self.points[ids], self.clearance[ids]

    def lower_clearance(self, ids, values):
        self.clearance[ids] = np.minimum(self.clearance[ids], values)

    def split_candidates(self, low, longest, most=None):
        if self.bound is None:
            self.longest = (self.cell_upper - self.cell_lower).max(axis=1)
            self.bound = self.reach.copy()
        ids = np.flatnonzero((self.longest > longest) & (self.bound >= low))
        points, clearance = self.gather(ids)
        lower, upper = self.cell_lower[ids], self.cell_upper[ids]
        farthest = np.maximum(points - lower, upper - points)
        # -inf clearance: not converged, the reach alone bounds it.
        attained = np.where(clearance == -np.inf, np.inf, clearance + np.linalg.norm(farthest, axis=1))
        bound = np.minimum(self.reach[ids], attained)
        self.bound[ids] = np.minimum(self.bound[ids], bound)
        keep = bound >= low
        ids, bound = ids[keep], bound[keep]
        keep = largest(bound, most)
        return ids[keep], bound[keep]

    def split_cells(self, ids, wall_slack):
        count, rows = len(ids), np.arange(len(ids))
        points, lower, upper = self.points[ids], self.cell_lower[ids], self.cell_upper[ids]
        axis = np.argmax(upper - lower, axis=1)
        middle = 0.5 * (lower[rows, axis] + upper[rows, axis])
        low_half = points[rows, axis] < middle
        kept_lower, kept_upper, other_lower, other_upper = lower.copy(), upper.copy(), lower.copy(), upper.copy()
        kept_upper[rows, axis] = np.where(low_half, middle, upper[rows, axis])
        kept_lower[rows, axis] = np.where(low_half, lower[rows, axis], middle)
        other_lower[rows, axis] = np.where(low_half, middle, lower[rows, axis])
        other_upper[rows, axis] = np.where(low_half, upper[rows, axis], middle)
        new_lower, new_upper = np.concatenate([kept_lower, other_lower]), np.concatenate([kept_upper, other_upper])
        centers, reach, wall = cell_bounds(new_lower, new_upper, lambda at: self.backend.distance(self.shape, at),
                                           wall_slack)
        reach = np.minimum(np.tile(self.reach[ids], 2), reach)
        self.cell_lower[ids], self.cell_upper[ids] = kept_lower, kept_upper
        self.reach[ids], self.wall[ids] = reach[:count], wall[:count]
        self.cell_lower = np.concatenate([self.cell_lower, other_lower])
        self.cell_upper = np.concatenate([self.cell_upper, other_upper])
        self.reach = np.concatenate([self.reach, reach[count:]])
        self.wall = np.concatenate([self.wall, wall[count:]])
        self.points = np.concatenate([self.points, centers[count:]])
        self.clearance = np.concatenate([self.clearance, np.full(count, -np.inf)])
        self.polished = np.concatenate([self.polished, np.zeros(count, dtype=bool)])
        new = np.arange(len(self.reach) - count, len(self.reach))
        if self.bound is not None:
            changed = np.concatenate([ids, new])
            self.longest = np.concatenate([self.longest, np.empty(count)])
            self.bound = np.concatenate([self.bound, np.empty(count)])
            self.longest[changed] = (self.cell_upper[changed] - self.cell_lower[changed]).max(axis=1)
            self.bound[changed] = self.reach[changed]
        return new

    def add_cells(self, cell_lower, cell_upper, reach, wall):
        count = len(reach)
        self.cell_lower = np.concatenate([self.cell_lower, cell_lower])
        self.cell_upper = np.concatenate([self.cell_upper, cell_upper])
        self.reach = np.concatenate([self.reach, reach])
        self.wall = np.concatenate([self.wall, wall])
        self.points = np.concatenate([self.points, 0.5 * (cell_lower + cell_upper)])
        self.clearance = np.concatenate([self.clearance, np.full(count, -np.inf)])
        self.polished = np.concatenate([self.polished, np.zeros(count, dtype=bool)])
        if self.bound is not None:
            self.longest = np.concatenate([self.longest, (cell_upper - cell_lower).max(axis=1)])
            self.bound = np.concatenate([self.bound, reach])
        return np.arange(len(self.reach) - count, len(self.reach))

    def tighten_reach(self, ids, centers, radii):
        if len(ids) and len(radii):
            self.reach[ids] = self.backend.tightened_reach(self.cell_lower[ids], self.cell_upper[ids], self.reach[ids],
                                                           centers, radii)

    def touched(self, new_centers, new_radii):
        nearest = self.backend.touched(self.points, self.clearance, new_centers, new_radii)
        ids = np.flatnonzero(nearest >= 0)
        return ids, self.points[ids], nearest[ids]

    def move(self, ids, centers, radii, steps, restarts=None, polish=False, ahead=None):
        self._move(ids, centers, radii, steps, restarts, polish)
        if ahead is not None:  # one after the other: on a CPU a launch costs only its work
            reached = ids[self.clearance[ids] >= ahead.low]
            more = np.sort(np.concatenate([reached, ahead.ids])).astype(np.int64)
            self._move(more, centers, radii, ahead.steps, None, True)

    def _move(self, ids, centers, radii, steps, restarts, polish):
        if len(ids) == 0:
            return
        backend, shape = self.backend, self.shape
        lower, upper = self.cell_lower[ids], self.cell_upper[ids]
        starts = None if restarts is None else restarts.points(ids, lower, upper, self.points[ids])
        neighbours, self.reach[ids] = backend.near_spheres(lower, upper, self.reach[ids], centers, radii,
                                                           return_bound=True)
        points, clearance = backend.converge(shape, self.points[ids], lower, upper, centers, radii, neighbours,
                                             steps, self.wall[ids], starts)
        if polish:
            better = clearance > self.clearance[ids]
            self.points[ids[better]] = points[better]
            self.clearance[ids[better]] = clearance[better]
        else:
            self.points[ids] = points
            self.clearance[ids] = clearance
        self.polished[ids] = polish


class DevicePrototypes(Prototypes):
    """Prototypes in a GPU's memory; each call launches kernels and copies back only its answer.

    A query (select, leaders, touched) runs a kernel that appends its matches (id, clearance,
    point, polish flag) to answer buffers through an atomic counter; one synchronising copy
    brings back the counter and a prefix of the buffers, sized from the last answers.

    Parameters
    ----------
    device : object
        The backend's device adapter, with ``upload(host, kind)``, ``empty(shape, kind)``,
        ``fill(array, value)``, ``fetch(*(array, count))`` (host copies of the first ``count``
        rows of each array, after one synchronisation), ``launch(kernel_name, threads, *args)``,
        ``spheres(centers, radii)`` (device copies, never empty), ``params`` (the shape's
        parameters on the device), ``h`` (the finite-difference step), ``write(array, start,
        host, kind)`` (rows from ``start`` replaced) and ``grow(array, rows, kind)`` (a device
        array of ``rows`` rows that begins with ``array``'s). Kinds are ``"float"``, ``"point"`` and
        ``"index"``. The kernels are ``max_all``, ``select_all``, ``touched_index_select``,
        ``gather_ids``, ``index_bound_ids``, ``index_fill_ids``, ``near_finish``, ``move_ids``,
        ``set_floats``, ``lower_floats``, ``split_mark``, ``split_cut``, ``cell_distances``, ``index_clear`` and
        ``index_insert_range`` of the backend's kernel text.
    spread : int
        Most threads per prototype in a move launch (a power of two; see :func:`lane_spread`):
        ``SPREAD_MAX`` on a GPU, 1 on a CPU device, where idle threads would be work.

    The spheres near a cell, and the prototypes a new sphere touches, are found through a
    :class:`~ndpack.backends.sphere_index.DeviceIndex`, built and queried on the device.
    Other parameters as in :class:`Prototypes`.
    """

    #: Neighbour-table columns allocated at first; grown to the widest row seen.
    FIRST_WIDTH = 8
    #: Answer rows copied back with the counter, at least; more after larger answers.
    FIRST_PREFIX = 64
    #: The arrays grow to at least this factor of their rows when cells split beyond them.
    GROWTH = 1.25
    #: The per-prototype arrays, and their kinds.
    ARRAYS = (("d_lower", "point"), ("d_upper", "point"), ("d_points", "point"), ("d_reach", "float"),
              ("d_wall", "float"), ("d_clearance", "float"), ("d_bound", "float"), ("d_polished", "index"))

    def __init__(self, device, cell_lower, cell_upper, reach, points, clearance, wall=None, spread=1):
        super().__init__(cell_lower, cell_upper, reach, points, clearance, wall)
        self.device = device
        self.spread = spread  # most threads per prototype of a move launch (1 on a CPU device)
        up = device.upload
        count = len(points)
        self.d_points, self.d_clearance = up(points, "point"), up(clearance, "float")
        self.d_polished = up(np.zeros(count, dtype=np.int64), "index")
        self.d_lower, self.d_upper, self.d_reach = up(cell_lower, "point"), up(cell_upper, "point"), up(reach, "float")
        self.d_wall = up(no_wall(count) if wall is None else wall, "float")
        self.d_bound = up(reach, "float")  # the fast mode's split bound per cell (see split_candidates)
        self.count = self.capacity = count  # the arrays' rows beyond count are room to grow
        # Answer buffers of the compacting kernels: at most one row per prototype.
        self.answers = (device.empty(count, "index"), device.empty(count, "float"),
                        device.empty(count, "point"), device.empty(count, "index"))
        self.d_counter, self.d_top = device.empty(1, "index"), device.empty(1, "float")
        # A window's largest clearance and the largest below it, and how many lie within it (window)
        self.d_window, self.d_late = device.empty(2, "float"), device.empty(1, "index")
        self.d_scratch = device.empty((1, 1), "index")  # the unused table of a bound-only index query
        self.d_no_first = device.empty(1, "point")  # the first points of a move that has none
        self.d_nearest = None  # (n, 1): the touched query's nearest new sphere per prototype
        self.sphere_index = DeviceIndex(self.dim, device)  # the spheres'
        self.touched_index = DeviceIndex(self.dim, device)  # a round's new spheres
        self.width = self.FIRST_WIDTH
        self.answered = {}  # kernel name -> its last two answers' rows (see _compact)
        self._window = FIRST_WINDOW
        self._steps = {}

    def __len__(self) -> int:
        return self.count

    def _host_copy(self, array):
        """The first ``count`` rows of device ``array`` on the host: for inspection and tests,
        not for rounds."""
        return self.device.fetch((array, self.count))[0]

    cell_lower = property(lambda self: self._host_copy(self.d_lower))
    cell_upper = property(lambda self: self._host_copy(self.d_upper))
    reach = property(lambda self: self._host_copy(self.d_reach))
    wall = property(lambda self: self._host_copy(self.d_wall))

    def lower_clearance(self, ids, values):
        if len(ids):
            up = self.device.upload
            self.device.launch("lower_floats", len(ids), up(ids, "index"), up(values, "float"), self.d_clearance)

    def split_candidates(self, low, longest, most=None):
        ids, bound, _, _, _ = self._compact(
            "split_mark", self.count, self.d_lower, self.d_upper, self.d_reach, self.d_points, self.d_clearance,
            self.d_bound, float(low), float(longest), fields=(0, 1), most=most)
        return ids.astype(np.int64), bound

    def split_cells(self, ids, wall_slack):
        # The halves' distances are evaluated by the kernel, on the device.
        device, count, first = self.device, len(ids), self.count
        self._reserve(first + count)
        self.count += count
        d_ids = device.upload(ids, "index")
        device.launch("split_cut", count, d_ids, self.d_lower, self.d_upper, self.d_reach, self.d_points,
                      self.d_clearance, self.d_polished, first)
        # A thread a half: each half's distance is a walk of the mesh's trees of its own.
        device.launch("cell_distances", 2 * count, d_ids, count, first, self.d_lower, self.d_upper, self.d_reach,
                      self.d_wall, self.d_bound, device.params, float(wall_slack))
        return np.arange(first, self.count)

    def add_cells(self, cell_lower, cell_upper, reach, wall):
        count, first = len(reach), self.count
        self._reserve(first + count)
        rows = {"d_lower": cell_lower, "d_upper": cell_upper, "d_points": 0.5 * (cell_lower + cell_upper),
                "d_reach": reach, "d_wall": wall, "d_clearance": np.full(count, -np.inf), "d_bound": reach,
                "d_polished": np.zeros(count, dtype=np.int64)}
        for name, kind in self.ARRAYS:
            self.device.write(getattr(self, name), first, rows[name], kind)
        self.count += count
        return np.arange(first, self.count)

    def _reserve(self, count):
        """Room for ``count`` prototypes in every array: they grow by ``GROWTH`` at least, so that
        few splits allocate (an allocation costs a synchronisation or a free in numba-cuda)."""
        if count <= self.capacity:
            return
        capacity = max(count, int(self.GROWTH * self.capacity) + 1024)
        for name, kind in self.ARRAYS:
            setattr(self, name, self.device.grow(getattr(self, name), capacity, kind))
        self.answers = tuple(self.device.empty(capacity, kind) for kind in ("index", "float", "point", "index"))
        self.capacity = capacity

    def _compact(self, kernel, *args, fields=(0, 1, 2, 3), scalars=(), most=None):
        """Run a kernel that appends matches, with one synchronisation: ids (m,) ascending, their
        clearances, points (m, d) and polish flags (those not among ``fields``, ascending
        positions in that order starting with the ids, come back None, uncopied), and a list of
        host copies of the small device arrays ``scalars``, copied in the same synchronisation.

        The first copy takes a prefix of each answer, twice the longer of this kernel's last two
        answers (a round's queries differ by orders of magnitude, and one kernel serves several:
        a selection the window and the polish ahead, the split marks each level); a longer answer
        is copied again whole, a second synchronisation. Against twice the last answer alone, the
        armadillo at 20,000 spheres copied again 20 answers of 170 instead of 40, for 35% more
        rows copied.
        With ``most`` (``fields`` holding the values, 1), only the rows of the ``most`` largest
        values come back (:func:`largest`): of a longer answer only the ids and values are copied,
        and the points and polish flags of the rows kept are gathered from the store (as a
        selection appends them; not for other kernels): a round takes at most ``MAX_CANDIDATES``
        candidates of a window that grows with the store (5 million prototypes at a million
        spheres of the armadillo).
        """
        device = self.device
        device.fill(self.d_counter, 0)
        device.launch(kernel, len(self), *args, self.d_counter, *self.answers)
        recent = self.answered.get(kernel, ())
        prefix = min(len(self), max(self.FIRST_PREFIX, 2 * max(recent, default=0)))
        wanted = [self.answers[field] for field in fields]
        counter, *answers = device.fetch(
            (self.d_counter, 1), *[(array, array.shape[0]) for array in scalars],
            *[(answer, prefix) for answer in wanted])
        extras = [answers.pop(0) for _ in scalars]
        count = int(counter[0])
        self.answered[kernel] = (*recent[-1:], count if most is None else min(count, most))
        if most is not None and count > max(prefix, most):
            return (*self._largest_rows(count, most, fields), extras)
        if count > prefix:
            answers = device.fetch(*[(answer, count) for answer in wanted])
        answers = [answer[:count] for answer in answers]
        if most is not None:
            keep = largest(answers[fields.index(1)], most)
            answers = [answer[keep] for answer in answers]
        order = np.argsort(answers[0])  # atomics append in any order; sorting makes runs repeatable
        out = [None] * 4
        for field, answer in zip(fields, answers):
            out[field] = answer[order]
        return (*out, extras)

    def _largest_rows(self, count, most, fields):
        """The ``count`` answers' rows of the ``most`` largest values, as :meth:`_compact` returns
        them (four fields, None where not among ``fields``): the ids and values copied, the
        points and polish flags gathered by id."""
        device = self.device
        ids, values = device.fetch((self.answers[0], count), (self.answers[1], count))
        keep = largest(values, most)
        ids, values = ids[keep], values[keep]
        order = np.argsort(ids)
        out = [ids[order], values[order], None, None]
        if 2 in fields or 3 in fields:
            rows = len(ids)
            d_points, _, d_flags = self._gathered(out[0])
            points, flags = device.fetch((d_points, rows), (d_flags, rows))
            for field, value in ((2, points), (3, flags)):
                out[field] = value if field in fields else None
        return out

    def _select(self, low=-np.inf, high=np.inf, unpolished=False, relative=-1.0, points=True, most=None):
        """:meth:`select`, and with ``relative >= 0`` the low bound raised to ``(1 - relative)``
        times the maximum where that is positive; the maximum is found on the device first.
        ``points=False``: the points and polish flags stay on the device (None). ``most``: as
        :meth:`_compact`."""
        if relative >= 0:
            self.device.fill(self.d_top, -np.inf)
            self.device.launch("max_all", len(self), self.count, self.d_clearance, np.inf, self.d_top)
        fields = (0, 1, 2, 3) if points else (0, 1)
        *rows, extras = self._compact("select_all", self.count, self.d_clearance, self.d_polished, self.d_points,
                                      float(low), float(high), int(unpolished), self.d_top, float(relative),
                                      fields=fields, scalars=(self.d_top,) if relative >= 0 else (), most=most)
        return (*rows, float(extras[0][0]) if extras else np.nan)

    def select(self, low=-np.inf, high=np.inf, unpolished=False):
        ids, clearance, _, _, _ = self._select(low, high, unpolished, points=False)
        return ids, clearance

    def candidates(self, low, most=None):
        ids, clearance, points, polished, _ = self._select(low, most=most)
        return ids, clearance, points, polished != 0

    def window(self, fraction, most=None, late=None):
        # The kernels take the window below a positive frontier only, at least ``low``: nothing is
        # selected at a run's end, when no clearance is positive.
        low = float(np.finfo(np.float32).tiny)  # a Python float: the kernels compile for float64 (ENTRY_TYPES)
        if late is None:
            ids, clearance, points, polished, top = self._select(low=low, relative=fraction, most=most)
            return ids, clearance, points, polished != 0, top, top
        # The late finds' rule on the device: four launches, one synchronisation (a rule applied on
        # the host took three when it held, in most rounds of a large packing).
        device, count = self.device, self.count
        floor, few = float(late[0]), int(late[1])
        device.fill(self.d_window, -np.inf)
        device.fill(self.d_late, 0)
        device.launch("max_all", len(self), count, self.d_clearance, np.inf, self.d_window)
        device.launch("window_count", len(self), count, self.d_clearance, self.d_window, float(fraction), low, few,
                      self.d_late)
        device.launch("window_below", len(self), count, self.d_clearance, self.d_window, float(fraction), self.d_late,
                      floor, few)
        ids, clearance, points, polished, (window, counted) = self._compact(
            "select_window", count, self.d_clearance, self.d_polished, self.d_points, low, self.d_window,
            float(fraction), self.d_late, floor, few, scalars=(self.d_window, self.d_late), most=most)
        top, below = float(window[0]), float(window[1])
        taken = top > 0 and top >= floor and int(counted[0]) < few and below > 0  # the kernels' rule
        return ids, clearance, points, polished != 0, top, below if taken else top

    def top(self, below=np.inf):
        self.device.fill(self.d_top, -np.inf)
        self.device.launch("max_all", len(self), self.count, self.d_clearance, float(below), self.d_top)
        return float(self.device.fetch((self.d_top, 1))[0][0])

    def leaders(self, k, window):
        k = min(k, len(self))
        relative = max(self._window, window)
        while True:
            ids, clearance, points, polished, top = self._select(relative=relative)
            low = top * (1 - relative) if top > 0 and relative < 1 else -np.inf
            kth = np.partition(clearance, len(ids) - k)[len(ids) - k] if len(ids) >= k else None
            # Done when it holds k leaders and every prototype within the window of the k-th.
            if low == -np.inf or (kth is not None and (kth <= 0 or low <= (1 - window) * kth)):
                break
            relative = min(1.0, relative * WIDEN)
        self._window = relative if len(ids) < 4 * k + 64 else max(window, relative / WIDEN)
        order = top_order(ids, clearance, k)
        kth = clearance[order[-1]]
        unpolished = ids[(clearance >= (1 - window) * kth) & (polished == 0)] if kth > 0 else ids[:0]
        return ids[order], clearance[order], points[order], unpolished

    def touched(self, new_centers, new_radii):
        up = self.device.upload
        d_centers, d_radii = up(new_centers, "point"), up(new_radii, "float")
        index = self.touched_index.sync(new_centers, new_radii, d_centers, d_radii)
        if self.d_nearest is None or self.d_nearest.shape[0] < len(self):
            self.d_nearest = self.device.empty((len(self), 1), "index")
        # The kernel sends each one's nearest new sphere back in the polish flags' place.
        ids, _, points, nearest, _ = self._compact(
            "touched_index_select", self.count, self.d_points, self.d_clearance, self.d_polished,
            d_centers, d_radii, *index, self.d_nearest, fields=(0, 2, 3))
        return ids, points, nearest.astype(np.int64)

    def gather(self, ids):
        count = len(ids)
        if count == 0:
            return np.empty((0, self.dim)), np.empty(0)
        out_points, out_clearance, _ = self._gathered(ids)
        points, clearance = self.device.fetch((out_points, count), (out_clearance, count))
        return points, clearance

    def _gathered(self, ids):
        """Device arrays of the points (k, d), clearances (k,) and polish flags (k,) of
        prototypes ``ids`` (k,), gathered on the device."""
        device, count = self.device, len(ids)
        out = device.empty(count, "point"), device.empty(count, "float"), device.empty(count, "index")
        device.launch("gather_ids", count, device.upload(ids, "index"), self.d_points, self.d_clearance,
                      self.d_polished, *out)
        return out

    def _tightened(self, d_ids, count, centers, radii, spread):
        """The spheres on the device, their index, and the tightened reach (k,) of the cells of
        ``d_ids`` (on the device, not yet stored)."""
        device = self.device
        d_centers, d_radii = device.spheres(centers, radii)
        index = self.sphere_index.sync(centers, radii, d_centers, d_radii)
        bound = device.empty(count, "float")
        device.launch("index_bound_ids", spread * count, d_ids, self.d_lower, self.d_upper, self.d_reach, d_centers,
                      d_radii, *index, self.d_scratch, bound, spread)
        return d_centers, d_radii, index, bound

    def tighten_reach(self, ids, centers, radii):
        count = len(ids)
        if count == 0 or len(radii) == 0:
            return
        d_ids = self.device.upload(ids, "index")
        bound = self._tightened(d_ids, count, centers, radii, lane_spread(count, self.spread))[3]
        self.device.launch("set_floats", count, d_ids, bound, self.d_reach)

    def _neighbours(self, ids, d_ids, centers, radii):
        """The spheres on the device and the (k, width) table of those near the cells of ``ids``
        (k,), padded with m.

        The same spheres as :meth:`Backend.near_spheres` finds (through the sphere index, in any
        order): one pass tightens each cell's reach (kept, on both sides, as the host store
        keeps it), one fills the rows.
        """
        device, count = self.device, len(ids)
        spread = lane_spread(count, self.spread)  # the index walks diverge as the moves do
        d_centers, d_radii, index, bound = self._tightened(d_ids, count, centers, radii, spread)
        found = device.empty(count, "index")
        while True:
            table = device.empty((count, self.width), "index")
            device.fill(self.d_counter, 0)
            device.launch("index_fill_ids", spread * count, d_ids, self.d_lower, self.d_upper, bound, d_centers,
                          d_radii, *index, found, table, spread)
            device.launch("near_finish", count, found, d_radii.shape[0], self.d_counter, table)
            widest, tightened = device.fetch((self.d_counter, 1), (bound, count))
            if np.isnan(tightened).any():  # index_near met a sphere id beyond the spheres
                raise RuntimeError(
                    "the device's sphere index is corrupt (a sphere id beyond the spheres); please report "
                    "this with the shape and backend, and use backend='warp' or 'numba' meanwhile"
                )
            if widest[0] <= self.width:
                device.launch("set_floats", count, d_ids, bound, self.d_reach)
                return d_centers, d_radii, table
            self.width = int(widest[0])

    def move(self, ids, centers, radii, steps, restarts=None, polish=False, ahead=None):
        moved = len(ids)
        if ahead is not None:  # the polished-only rows after the moved ones, in the same launch
            ids = np.concatenate([ids, ahead.ids])
        count = len(ids)
        if count == 0:
            return
        device = self.device
        d_ids = device.upload(ids, "index")
        d_centers, d_radii, table = self._neighbours(ids, d_ids, centers, radii)
        # The random starts are drawn in the kernel (ndpack.backends.restarts): only the first
        # points, where there are any, are copied up.
        first = None if restarts is None else restarts.first
        tries, stream = (0, 0) if restarts is None else (restarts.tries, restarts.stream)
        d_first = self.d_no_first if first is None else device.upload(first, "point")
        spread = lane_spread(count, self.spread)
        first_rows = 0 if first is None else len(first)
        polish_steps, polish_low = (steps, np.inf) if ahead is None else (ahead.steps, ahead.low)
        device.launch("move_ids", spread * count, d_ids, d_first, first_rows, tries, np.uint64(stream), self.d_points,
                      self.d_clearance, self.d_polished, self.d_lower, self.d_upper, self.d_wall, device.params,
                      d_centers, d_radii, table, self._schedule(steps), device.h, int(polish), spread,
                      self._schedule(polish_steps), float(polish_low), moved, lanes=spread)

    def _schedule(self, steps):
        """A cooling schedule (T,) on the device; the driver has two, each copied once."""
        key = (id(steps), len(steps))
        if key not in self._steps:
            self._steps[key] = (steps, self.device.upload(steps, "float"))
        return self._steps[key][1]
