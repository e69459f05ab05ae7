"""Soft-sphere contacts: neighbour lists, and the forces of overlapping spheres pushing apart.

What the dense-bed driver (:mod:`ndpack.drivers.dense`) relaxes. Two spheres ``i``, ``j`` whose
centres are closer than ``r_i + r_j`` overlap by ``delta = r_i + r_j - |c_i - c_j|`` and push
each other apart with a force of ``delta`` along the line of centres (a harmonic spring of unit
stiffness: the energy ``delta**2 / 2`` a pair). A periodic axis takes the nearest image.

The neighbour list is SciPy's k-d tree (``query_pairs``, periodic through ``boxsize``), in a
compressed row form: each pair once, under its lower-numbered sphere, in a fixed order, so the
forces come out the same on every machine. The forces run in NumPy (the reference) or compiled
by Numba; the two agree to rounding (their sums run in other orders).
"""

from __future__ import annotations

import functools

import numpy as np


def neighbour_lists(centers: np.ndarray, reach: float, period=None) -> tuple[np.ndarray, np.ndarray]:
    """Each sphere's neighbours: the centres within ``reach`` of its own (nearest images along
    ``period``'s axes, a :class:`~ndpack.geometry.period.Period`, or None).

    Returns ``starts`` (n + 1,) int64 and ``neighbours`` (m,) int64: sphere ``i``'s neighbours
    numbered above ``i`` are ``neighbours[starts[i]:starts[i + 1]]``, ascending; each pair once.
    """
    from scipy.sparse import coo_matrix
    from scipy.spatial import cKDTree

    count = len(centers)
    if period is None:
        tree = cKDTree(centers)
    else:
        tree, _ = period.tree(centers, reach)
    pairs = tree.query_pairs(reach, output_type="ndarray")  # i < j in each
    rows, cols = pairs[:, 0], pairs[:, 1]
    # By sphere, then neighbour (the same lists however the tree found them): SciPy's compressed
    # rows, 4x faster than NumPy's lexsort at 100,000 spheres.
    table = coo_matrix((np.ones(len(rows), dtype=np.int8), (rows, cols)), shape=(count, count)).tocsr()
    table.sort_indices()
    return table.indptr.astype(np.int64), table.indices.astype(np.int64)


def periods(period, dim: int) -> np.ndarray:
    """Each axis's period (d,) float64, infinite where the axis does not wrap (or no ``period``)."""
    return np.full(dim, np.inf) if period is None else np.asarray(period.lengths, dtype=np.float64)


def contact_forces(centers, radii, starts, neighbours, lengths, compiled: bool = True):
    """The push of each sphere's overlapping neighbours.

    Parameters
    ----------
    centers : (n, d) float64
    radii : (n,) float64
    starts, neighbours : int64
        The neighbour lists (:func:`neighbour_lists`), wide enough for every overlapping pair.
    lengths : (d,) float64
        Each axis's period, ``inf`` where it does not wrap (:func:`periods`).
    compiled : bool
        Numba; False for the NumPy reference.

    Returns
    -------
    forces : (n, d) float64
        The sum of ``delta * (c_i - c_j) / |c_i - c_j|`` over the overlapping neighbours ``j``.
    energy : (n,) float64
        The energy ``delta**2 / 2`` of the sphere's pairs with higher-numbered neighbours.
    overlap : (n,) float64
        The largest ``delta / (r_i + r_j)`` of its pairs, 0 where none overlaps.
    """
    centers = np.ascontiguousarray(centers, dtype=np.float64)
    radii = np.ascontiguousarray(radii, dtype=np.float64)
    lengths = np.ascontiguousarray(lengths, dtype=np.float64)
    count, dim = centers.shape
    forces, energy, overlap = np.zeros((count, dim)), np.zeros(count), np.zeros(count)
    if compiled:
        _kernels()(centers, radii, starts, neighbours, lengths, forces, energy, overlap)
        return forces, energy, overlap
    rows, cols = pair_rows(starts), neighbours
    delta = centers[rows] - centers[cols]
    wraps = np.isfinite(lengths)
    delta[:, wraps] -= lengths[wraps] * np.floor(delta[:, wraps] * (1.0 / lengths[wraps]) + 0.5)
    distance = np.sqrt((delta * delta).sum(axis=1))
    reach = radii[rows] + radii[cols]
    depth = np.maximum(reach - distance, 0.0)
    touching = depth > 0
    rows, cols, delta, distance, depth, reach = (values[touching] for values in
                                                 (rows, cols, delta, distance, depth, reach))
    push = depth / np.where(distance == 0.0, 1.0, distance)
    along = push[:, None] * delta
    coincident = distance == 0.0  # two centres at one point part along the first axis
    along[coincident, 0] = depth[coincident]
    np.add.at(forces, rows, along)
    np.add.at(forces, cols, -along)
    np.add.at(energy, rows, 0.5 * depth * depth)
    np.maximum.at(overlap, rows, depth / reach)
    np.maximum.at(overlap, cols, depth / reach)
    return forces, energy, overlap


def close_pairs(centers: np.ndarray, reach: float, period=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pairs of centres (n, d) within ``reach`` (nearest images along ``period``'s axes):
    the lower and the higher sphere (m,) int64 of each, and their distance (m,) float64."""
    starts, cols = neighbour_lists(centers, reach, period)
    rows = pair_rows(starts)
    if period is None:
        delta = centers[rows] - centers[cols]
    else:
        delta = period.difference(centers[rows], centers[cols])
    return rows, cols, np.sqrt(np.einsum("ij,ij->i", delta, delta))


def pair_rows(starts: np.ndarray) -> np.ndarray:
    """The lower sphere (m,) int64 of each listed pair, from the lists' ``starts`` (n + 1,)."""
    return np.repeat(np.arange(len(starts) - 1), np.diff(starts))


def _forces(centers, radii, starts, neighbours, lengths, forces, energy, overlap):
    count, dim = centers.shape
    inverse = np.zeros(dim)  # 1 / period, 0 where the axis does not wrap
    for k in range(dim):
        if lengths[k] < np.inf:
            inverse[k] = 1.0 / lengths[k]
    step = np.empty(dim)
    push_i = np.empty(dim)  # sphere i's forces, summed here and stored once
    for i in range(count):
        for k in range(dim):
            push_i[k] = 0.0
        energy_i, worst_i, radius_i = 0.0, 0.0, radii[i]
        for t in range(starts[i], starts[i + 1]):
            j = neighbours[t]
            squared = 0.0
            for k in range(dim):
                offset = centers[i, k] - centers[j, k]
                if inverse[k] != 0.0:
                    offset -= lengths[k] * np.floor(offset * inverse[k] + 0.5)
                step[k] = offset
                squared += offset * offset
            reach = radius_i + radii[j]
            if squared >= reach * reach:
                continue
            distance = np.sqrt(squared)
            depth = reach - distance
            energy_i += 0.5 * depth * depth
            share = depth / reach
            worst_i = max(worst_i, share)
            overlap[j] = max(overlap[j], share)
            if distance == 0.0:  # two centres at one point part along the first axis
                push_i[0] += depth
                forces[j, 0] -= depth
                continue
            scale = depth / distance
            for k in range(dim):
                push_i[k] += scale * step[k]
                forces[j, k] -= scale * step[k]
        for k in range(dim):
            forces[i, k] += push_i[k]
        energy[i] = energy_i
        overlap[i] = max(overlap[i], worst_i)


def fire_move(centers, velocity, forces, dt: float, alpha: float, compiled: bool = True) -> None:
    """One FIRE step's motion, in place: ``velocity += dt * forces``, then turned towards the
    forces (``(1 - alpha) v + alpha |v| F / |F|``), then ``centers += dt * velocity``.

    centers, velocity, forces : (n, d) float64
    """
    if compiled:
        _fire_kernel()(centers, velocity, forces, dt, alpha)
        return
    velocity += dt * forces
    force_norm = float(np.sqrt(np.vdot(forces, forces)))
    if force_norm > 0:
        speed = float(np.sqrt(np.vdot(velocity, velocity)))
        velocity *= 1.0 - alpha
        velocity += (alpha * speed / force_norm) * forces
    centers += dt * velocity


def largest_move(centers, before, lengths, compiled: bool = True) -> float:
    """The largest squared distance any centre (n, d) moved from ``before`` (n, d), nearest images
    along the periodic axes (``lengths``, :func:`periods`)."""
    if compiled:
        return float(_move_kernel()(centers, before, lengths))
    moved = centers - before
    wraps = np.isfinite(lengths)
    moved[:, wraps] -= lengths[wraps] * np.floor(moved[:, wraps] / lengths[wraps] + 0.5)
    return float(np.max(np.einsum("ij,ij->i", moved, moved), initial=0.0))


def _fire(centers, velocity, forces, dt, alpha):
    count, dim = centers.shape
    for i in range(count):  # serial sums, in order: the same numbers as NumPy's
        for k in range(dim):
            velocity[i, k] += dt * forces[i, k]
    squared_force, squared_speed = 0.0, 0.0
    for i in range(count):
        for k in range(dim):
            squared_force += forces[i, k] * forces[i, k]
            squared_speed += velocity[i, k] * velocity[i, k]
    turn = alpha * np.sqrt(squared_speed) / np.sqrt(squared_force) if squared_force > 0 else 0.0
    keep = 1.0 - alpha if squared_force > 0 else 1.0
    for i in range(count):
        for k in range(dim):
            velocity[i, k] = keep * velocity[i, k] + turn * forces[i, k]
            centers[i, k] += dt * velocity[i, k]


def _largest_move(centers, before, lengths):
    count, dim = centers.shape
    largest = 0.0
    for i in range(count):
        squared = 0.0
        for k in range(dim):
            step = centers[i, k] - before[i, k]
            if lengths[k] < np.inf:
                step -= lengths[k] * np.floor(step / lengths[k] + 0.5)
            squared += step * step
        largest = max(largest, squared)
    return largest


@functools.cache
def _compiled():
    """The kernels compiled by Numba (imported at the first call, so ``import ndpack`` stays
    light). Serial: on 2 cores, threads over the spheres of 10,000 took the forces from 1.9 ms to
    8.5 ms a step, as OpenMP's waiting threads took the core the step's serial work needed
    (``OMP_WAIT_POLICY=passive``: 2.0 ms), and a step is too short to share."""
    import numba

    from ..log import numba_functions

    numba_functions(__name__, "the dense beds' contact forces", 2.0)
    return (numba.njit(cache=True)(_forces), numba.njit(cache=True)(_fire),
            numba.njit(cache=True)(_largest_move))


def _kernels():
    return _compiled()[0]


def _fire_kernel():
    return _compiled()[1]


def _move_kernel():
    return _compiled()[2]
