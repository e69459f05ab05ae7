"""How a round chooses its spheres: the two strategies of the ProtoSphere driver.

The driver (:func:`ndpack.drivers.greedy.protosphere.pack`) runs the same loop in both modes: choose spheres,
insert them, then let the strategy prepare the next round. A strategy is an object with two
methods over the run's state (:class:`ndpack.drivers.greedy.protosphere.RunState`):

``choose(state, min_radius, room, max_radius=inf) -> (centers (k, d), radii (k,))``
    The spheres of this round, largest clearance first, mutually disjoint, at most ``room``,
    none below ``min_radius``; none when no prototype has room. A prototype whose clearance
    exceeds ``max_radius`` gives a sphere of ``max_radius`` at its point (so the clearance
    field still says where: the largest gaps first).
``after_round(state, centers, radii, room)``
    After the round's spheres ``centers`` (k, d), ``radii`` (k,) are inserted: the prototypes
    they touched converge again, and whatever else the strategy does between rounds (the fast
    mode splits cells, and restarts the touched and the new prototypes together), knowing
    that at most ``room`` more spheres are wanted; not called after the last round.

:class:`Faithful` is the paper's round on a fixed grid; :class:`Fast` takes a window of
candidates a round and refines the grid where gaps have become small. Only the fast mode keeps
per-cell bookkeeping, so a faithful run builds none of it, until the driver's final search
(:meth:`~ndpack.drivers.greedy.protosphere.RunState.search`, for a strategy whose ``searches`` is True) refines
its grid where no prototype has room left.
"""

from __future__ import annotations

import numpy as np

from ...backends.prototypes import PolishAhead, top_order
from .conflicts import disjoint_greedy

#: Candidates within this fraction of the best clearance are polished (moved further, with a
#: finer schedule) before any of them becomes a sphere.
POLISH_WINDOW = 0.05
#: Fast mode: candidates within this fraction of the largest clearance become spheres in one round
#: (those disjoint from the larger ones kept). 0.2 takes half the rounds of 0.1 for 0.07-0.17% less
#: fill (unit cube and armadillo at 100,000 spheres; docs/benchmarks.md); 0.3 loses 0.3%.
FAST_WINDOW = 0.2
#: Fast mode: a cell splits in two (across its longest side) while that side is longer than this
#: many times the largest clearance and the cell could still hold a candidate, so that the gaps
#: being filled are never much smaller than the cells that search for them.
SPLIT_RATIO = 4.0
#: Fast mode on a launch-bound backend (a GPU): the split ratio there, ``SPLIT_RATIO`` too, as
#: measured. Finer cells find a size's gaps before the frontier comes down to them (with 4, many
#: are found after the round of their size): 2.5 took the armadillo at 100,000 spheres in 34
#: rounds instead of 50 and filled 0.5% more, but 2.72 s against 2.07 s on an H100 (Warp): 3.7x
#: the prototypes moved, whose move launches became bound by throughput (27 against 14 ms each),
#: and more candidates for the host's conflict check (docs/benchmarks.md, issue 48).
SPLIT_RATIO_AHEAD = SPLIT_RATIO
#: Fast mode: late finds (candidates at the last round's size, found in split cells or by
#: restarts) join the next level's round when they are fewer than ``SMALL_ROUND`` and fewer than
#: ``SMALL_ROUND_SHARE`` of the spheres so far, and always when fewer than ``SMALL_ROUND_FIRST``
#: (see :meth:`Fast.choose`). On a GPU a round costs its launches' latency whatever its size; the share
#: keeps small counts from merging most of a round. Against a flat 64: 25-38% fewer rounds in the
#: armadillo and the unit cube at 100,000 spheres for 0.02% less fill or none (2 cores;
#: docs/benchmarks.md).
SMALL_ROUND = 1024
SMALL_ROUND_FIRST, SMALL_ROUND_SHARE = 64, 1 / 16
#: Fast mode: rounds of polishing the chosen candidates before the choice is made among the
#: polished ones only (:meth:`Fast.choose`).
POLISH_PASSES = 2
#: Fast mode on a launch-bound backend (a GPU, :attr:`~ndpack.backends.base.Backend.launch_bound`):
#: after a round, every unpolished prototype above this fraction of its frontier is polished, in
#: the launch that moves the touched and new prototypes (a
#: :class:`~ndpack.backends.prototypes.PolishAhead`), so that the next rounds' windows are mostly
#: polished already and their choices need no polish launch of their own: lanes a latency-bound
#: launch leaves idle on a GPU, but work on a CPU, where it stays off. The next round's window
#: starts near ``(1 - FAST_WINDOW)**2`` of the frontier, but one whose candidates are few (late
#: finds) reaches further down (see ``SMALL_ROUND``): with ``(1 - FAST_WINDOW)**2`` the armadillo
#: at 100,000 spheres still made 8.7 polish launches a run (3 seeds), each as long as a move
#: launch's chain; with ``(1 - FAST_WINDOW)**3`` 2 (the cube and the square at 10,000: 3.7 and 10.3
#: against 2 and 3), and the same fill within 0.02% (numba with a GPU's policies, 2 cores;
#: docs/benchmarks.md, issue 48's seventh step).
POLISH_AHEAD = (1 - FAST_WINDOW) ** 3
#: The polish ahead starts where the polish schedule has cooled to this ``eps``: 21 of its 60
#: steps in the fast mode, a little above where a move's schedule stops (``FAST_EPS_END``), down to
#: the polish's end. It follows a converged move, or polishes prototypes that converged in an
#: earlier round, so the schedule's long first steps would redo travel already made, while the
#: tail takes the zig-zag the rest of the way to its Voronoi node. A GPU's move launch lasts as long
#: as its longest prototype's chain of distance evaluations, the move's (52) and then its polish's:
#: 61 with the whole schedule, 21 with this tail. With a GPU's policies (numba, 2 cores;
#: ``bench/ahead_tail.py``) the unit cube at 10,000 spheres filled 0.08% less than with the whole
#: schedule (0.14% below the faithful mode), the armadillo at 100,000 no less.
AHEAD_EPS_START = 3e-4
#: Fast mode: at most this many candidates a round (bounds the host's conflict check).
MAX_CANDIDATES = 1 << 16
#: Fast mode stops splitting cells at this many prototypes (memory).
MAX_PROTOTYPES = 16_000_000
#: Fast mode: at most this many cells split after a round per sphere still wanted (``n`` less
#: those placed), so that the last rounds, which want few spheres, split few cells.
SPLITS_PER_SPHERE = 8


def _usable(state, clearance, min_radius, max_radius=np.inf):
    """Candidates as spheres: radii (k,), their clearances less the safety margin, at most
    ``max_radius``, and the positions (j,) of those not below ``min_radius`` (or the margin)."""
    radii = np.minimum(clearance - state.margin, max_radius)
    return radii, np.flatnonzero(radii >= max(min_radius, state.margin))


def capped(state, clearance, max_radius):
    """Whether each clearance (k,) gives a sphere of ``max_radius`` (k,) bool: such a candidate
    needs no polish, since a better place would not make its sphere larger."""
    return clearance - state.margin >= max_radius


def _snug(state, centers, clearance, radii, max_radius):
    """A round's chosen spheres (centres (k, d), radii (k,), the clearances (k,) at those centres),
    those capped at ``max_radius`` moved until they touch their nearest obstacle
    (:meth:`~ndpack.drivers.greedy.protosphere.RunState.snug`), and those that then meet one kept before them
    dropped (they were disjoint where they stood): centres (j, d) and radii (j,)."""
    moved = capped(state, clearance, max_radius) & (clearance - state.margin > radii)
    if not moved.any():
        return centers, radii
    centers, radii = centers.copy(), radii.copy()
    centers[moved] = state.snug(centers[moved], clearance[moved], radii[moved])
    keep = disjoint_greedy(centers, radii, state.margin, state.period)
    return centers[keep], radii[keep]


def _tightest_first(usable, clearance, full):
    """Positions ``usable`` (j,) in the order the choice takes them: those ``full`` (capped at
    ``max_radius``, all of one radius) first, the tightest fit (smallest clearance) first, then
    the others as they came (largest first). Equal spheres put first in the largest gaps leave
    gaps just too small for one more between them: in the unit cube (radius 0.025, fast mode,
    numba) largest first filled 0.388, tightest first 0.420 (both moved to touch; neither
    moved and largest first, 0.359)."""
    first = usable[full[usable]]
    return np.concatenate([first[np.argsort(clearance[first], kind="stable")], usable[~full[usable]]])


def fast_window(dim: int) -> float:
    """The fast mode's window in ``dim`` dimensions: ``FAST_WINDOW`` up to 3-D, then narrower as
    ``FAST_WINDOW * (3 / dim)**3``: 0.084 in 4-D, 0.043 in 5-D, 0.025 in 6-D and above (narrower
    still, a 12-D ball with a hole on a grid of 2 took 30x the time: its rounds place few spheres).

    A round's spheres are chosen with the clearances before any of them is placed; a sphere's
    gaps (where the faithful mode would put larger spheres before the window's smaller ones)
    hold more room relative to it the higher the dimension, and a window's radii span more of
    the packing's spheres, (1 - window)**-d. At 0.2 the fast mode filled 1-2% less than the
    faithful one from 4-D up; at these windows, with ties taken as :func:`_ties_first` takes
    them, within the seeds' spread of it (bench/fast_fill.py). A window of 0.05 against 0.2 took
    172 rounds against 24 and 1.5x the time (5-D ball with a hole, 20,000 spheres, 2 cores).
    """
    return FAST_WINDOW if dim <= 3 else FAST_WINDOW * (3 / min(dim, 6)) ** 3


#: Fast mode in ``TIE_DIMS``: candidates within this fraction of the round's largest
#: uncapped clearance are a tie (a ridge of equal gaps, as in a spherical shell; see :func:`_ties_first`).
TIE = 1e-3
#: A tie's candidate that touches no sphere keeps this many of its radii clear of those chosen before it.
SEED_GAP = 2.0
#: A tie's candidate touches a sphere when its clearance ball comes within this fraction of its radius of it.
CONTACT = 0.01
#: The tie rule's dimensions, the lowest and highest. Measured in 3-D it gained in a cylinder and a
#: shell (0.9%, 0.5%) but lost 0.4% in a slab (2,000 spheres, three seeds); in a 12-D shell on a
#: grid of 2 (every sphere of the largest size) it took 19 rounds for 500 spheres, 30x the time,
#: for the same fill. Elsewhere the plain choice.
TIE_DIMS = (4, 6)


def _slack(state, points, clearance):
    """The way (k,) from each clearance ball (``points`` (k, d), ``clearance`` (k,)) to its nearest
    sphere, inf where none comes within ``4 * CONTACT`` of its radius."""
    centers, radii = state.obstacles
    out = np.full(len(points), np.inf)
    if len(radii) == 0 or len(points) == 0:
        return out
    reach = clearance * (1 + 4 * CONTACT) + state.margin
    table = state.backend.near_spheres(points - reach[:, None], points + reach[:, None], reach, centers, radii)
    if table.shape[1] == 0:
        return out
    listed = table < len(radii)  # rows are padded with len(radii)
    near = np.where(listed, table, 0)
    gap = np.linalg.norm(points[:, None, :] - centers[near], axis=2) - radii[near] - clearance[:, None]
    return np.where(listed, gap, np.inf).min(axis=1)


def _ties_first(state, usable, points, clearance, radii, full):
    """A round's order ``usable`` (j,) and the radii (j,) its conflict check gives them, with ties
    taken as the faithful mode takes them.

    In ``TIE_DIMS``, where several uncapped candidates share the largest clearance (within
    ``TIE``: a ridge of equal gaps, as between the walls of a spherical shell, where every point
    of the ridge is a node), the faithful mode places them one by one, each touching those before it, since its
    touched prototypes converge again beside the new sphere; a fast round would keep any
    disjoint subset, equal spheres parked at random along the ridge (43 spheres of the largest
    size in a 4-D shell against the faithful mode's 51; 1.9% less fill at 1,000 spheres). So a
    round with a tie takes the tie only: first those that touch a sphere already placed, then
    those that touch none, each of these only ``SEED_GAP`` radii clear of those chosen before it
    (the room between is for spheres that will touch both). The others wait for the next round.
    """
    grown = radii[usable]
    if not TIE_DIMS[0] <= state.dim <= TIE_DIMS[1]:
        return usable, grown
    capped_first, free = usable[full[usable]], usable[~full[usable]]  # free: largest first
    if len(free) < 2:
        return usable, grown
    tie = free[: int(np.count_nonzero(clearance[free] >= (1 - TIE) * clearance[free[0]]))]
    if len(tie) < 2:
        return usable, grown
    touching = _slack(state, points[tie], clearance[tie]) <= CONTACT * clearance[tie]
    seeds = tie[~touching]
    usable = np.concatenate([capped_first, tie[touching], seeds])
    grown = radii[usable].copy()
    grown[len(usable) - len(seeds):] *= 1 + SEED_GAP / 2
    return usable, grown


class Faithful:
    """The paper's round: the largest clearance becomes a sphere, or up to ``batch`` of the
    largest that are mutually disjoint, largest first (``batch = 1``: the exact greedy order)."""

    name = "faithful"
    searches = True  # the driver's final search refines the cells before the run stops for room

    def __init__(self, batch: int = 1):
        self.batch = batch

    def leaders(self, state, take, max_radius=np.inf):
        """The ``take`` largest clearances after polishing, largest first: ids (k,), clearances
        (k,) and points (k, d).

        Every unpolished prototype within ``POLISH_WINDOW`` of the ``take``-th best is polished
        first, unless that one already gives a sphere of ``max_radius``. Clearances are attained
        values, so polishing only raises them: once the leaders are all polished, the largest
        clearance is the best Voronoi node to the polish accuracy.
        """
        while True:
            ids, clearance, points, unpolished = state.prototypes.leaders(take, POLISH_WINDOW)
            if len(unpolished) == 0 or capped(state, clearance[-1], max_radius):
                return ids, clearance, points
            state.polish(unpolished)

    def choose(self, state, min_radius, room, max_radius=np.inf):
        _, clearance, centers = self.leaders(state, min(self.batch, room), max_radius)
        radii, usable = _usable(state, clearance, min_radius, max_radius)
        centers, radii = _snug(state, centers[usable], clearance[usable], radii[usable], max_radius)
        # Same-round candidates know nothing of each other: keep those clear of the ones kept.
        chosen = disjoint_greedy(centers, radii, state.margin, state.period)
        return centers[chosen], radii[chosen]

    def after_round(self, state, centers, radii, room):
        state.settle(centers, radii)


class Fast:
    """Fast mode: every candidate within ``window`` of the frontier becomes a sphere where it is
    disjoint from the larger ones, and cells split where their gaps have become small.

    Keeps the last round's frontier; the prototype store keeps, per cell, its longest side and
    an upper bound of its clearance (so that a round looks only at cells that may split). With ``polish_ahead``
    (a fraction, see ``POLISH_AHEAD``) each round ends by polishing the unpolished prototypes
    above that fraction of its frontier; None polishes only the candidates a choice keeps.
    """

    name = "fast"
    searches = True

    def __init__(self, state, window: float | None = None, ratio: float = SPLIT_RATIO,
                 polish_ahead: float | None = None):
        self.window = fast_window(state.dim) if window is None else window
        self.ratio, self.polish_ahead = ratio, polish_ahead
        self.ties = True  # ties taken as the faithful mode takes them (:func:`_ties_first`)
        self.frontier = np.inf  # the last round's largest clearance, late finds aside
        self.ahead_steps = None  # the polish ahead's schedule (:func:`ahead_schedule`), once needed

    def choose(self, state, min_radius, room, max_radius=np.inf):
        """Every candidate within the window below the frontier or above it, largest first, kept
        where it is disjoint from the larger ones kept.

        The frontier is the largest clearance, unless few candidates lie within the window below
        it (see ``SMALL_ROUND``) and they reach the last round's window: gaps found late (in
        split cells, by restarts) at the last round's size. Those join the next level's round
        (the frontier is the largest clearance below them) instead of taking a round alone.
        Where the largest clearance exceeds ``max_radius`` the frontier is ``max_radius`` (plus
        the margin): every candidate within the window below it or above it gives a sphere, of
        ``max_radius`` where its clearance exceeds it.

        Only the candidates the choice keeps are polished (the capped ones need none), and the
        choice is made again with their polished clearances: a candidate that a larger one
        blocks is touched by that sphere and converges again anyway, so polishing it would be
        lost. After ``POLISH_PASSES`` passes the choice is made among polished candidates only
        (the others wait for the next round).
        """
        store, window = state.prototypes, self.window
        few = min(SMALL_ROUND, max(SMALL_ROUND_FIRST, int(SMALL_ROUND_SHARE * state.count)))
        ceiling = max_radius + state.margin  # a clearance above it gives a sphere of max_radius
        passes = 0
        while True:
            # One query, one sync on a GPU, the late finds' rule included; no more candidates than
            # a round takes.
            ids, clearance, points, polished, top, frontier = store.window(
                window, most=MAX_CANDIDATES, late=((1 - window) * self.frontier, few))
            if top <= 0:
                return np.empty((0, state.dim)), np.empty(0)
            if top > ceiling:
                frontier = ceiling
                ids, clearance, points, polished = store.candidates((1 - window) * ceiling, MAX_CANDIDATES)
            order = top_order(ids, clearance, min(MAX_CANDIDATES, len(ids)))
            ids, clearance, points, polished = ids[order], clearance[order], points[order], polished[order]
            full = capped(state, clearance, max_radius)
            polished = polished | full
            radii, usable = _usable(state, clearance, min_radius, max_radius)
            usable = _tightest_first(usable, clearance, full)
            grown = radii[usable]  # the radii the conflict check gives them
            if self.ties:
                usable, grown = _ties_first(state, usable, points, clearance, radii, full)
            chosen = usable[disjoint_greedy(points[usable], grown, state.margin, state.period)[:room]]
            waiting = ids[chosen[~polished[chosen]]]
            if len(waiting) == 0:
                break
            if passes >= POLISH_PASSES:
                ready_at = polished[usable]
                ready = usable[ready_at]
                chosen = ready[disjoint_greedy(points[ready], grown[ready_at], state.margin, state.period)[:room]]
                if len(chosen):
                    break
            state.polish(np.sort(waiting))
            passes += 1
        self.frontier = frontier
        return _snug(state, points[chosen], clearance[chosen], radii[chosen], max_radius)

    def after_round(self, state, centers, radii, room):
        self.refine(state, SPLITS_PER_SPHERE * room, state.touched(centers, radii), self.polish_ahead)

    def refine(self, state, most=None, touched=None, polish_ahead=None):
        """Split in two, across their longest side, the cells longer than ``ratio`` times the
        round's frontier whose clearance bound reaches the candidates' window; repeat on the
        halves; then the new halves' prototypes converge, in one launch. Returns how many split.

        A level's halves are split again on their reach, tightened by the spheres (the bound a
        converged prototype adds, its clearance plus the way to the cell's farthest corner,
        exceeds half the cell's longest side, so it could keep a cell this long from splitting
        only where its prototype had died), so that no prototype moves between levels: on a GPU
        a move launch costs its longest convergence however few prototypes move, and a level
        each had cost a launch, a neighbour table and its synchronisations.

        The prototypes the round's spheres ``touched`` (a :class:`~ndpack.drivers.greedy.protosphere.Touched`)
        restart in the same launch; a touched prototype whose cell splits restarts in its half.
        With ``polish_ahead`` (a fraction of the frontier, see ``POLISH_AHEAD``), every
        unpolished prototype above it ends the round polished: in the same launch again, those
        that converge above it continuing with the polish schedule's tail (:func:`ahead_schedule`).

        Work per round follows the cells that may split, not all cells. The bound stays valid as
        spheres arrive (clearances only shrink), so a cell is looked at again only once the
        window has come down to it. At most ``most`` cells split, those of the largest bounds first
        (the others wait, their bounds kept): the last rounds of a run want few spheres, and a
        level of cells split for them would cost more than they do.
        """
        store, top = state.prototypes, self.frontier
        if touched is not None:  # not moved yet: the clearance at their points, with the new spheres
            store.lower_clearance(touched.ids, touched.gap)
        total, made = 0, []
        for _ in range(4 * state.dim):
            if state.out_of_time():  # the run ends after this round: split no more
                break
            low = (1 - self.window) * top
            allowed = max(0, MAX_PROTOTYPES - len(store))
            if most is not None:
                allowed = min(allowed, most - total)
            ids, bound = store.split_candidates(low, max(self.ratio * top, 1e3 * state.margin), most=allowed)
            if len(ids) > allowed:  # the largest bounds first (ties: the lower id, as the ids come ascending)
                ids = np.sort(ids[top_order(ids, bound, allowed)])
            if len(ids) == 0:
                break
            new = store.split_cells(ids, state.wall_slack)
            store.tighten_reach(np.concatenate([ids, new]), *state.obstacles)
            made.append(new)
            total += len(ids)
        # The touched first (their first points are theirs), then the new ones from their centres.
        moving = np.concatenate([touched.ids if touched is not None else np.empty(0, np.int64), *made])
        ahead = None
        if polish_ahead is not None:  # the new ones are not converged (-inf): none of them is selected
            low = polish_ahead * top
            waiting, _ = store.select(low=low, unpolished=True)
            if self.ahead_steps is None:  # one array for the run: a device store copies each new one up
                self.ahead_steps = ahead_schedule(state.polish_steps)
            ahead = PolishAhead(self.ahead_steps, low,
                                np.setdiff1d(waiting, moving, assume_unique=True))
        state.reconverge(moving, None if touched is None else touched.pushed, ahead=ahead)
        return total


#: Size-distribution driver: a round places the next radii down to this fraction below the
#: largest left (each sphere gets the largest radius left that fits where it goes).
SIZE_BAND = 0.05


class Sized(Fast):
    """The fast round for a list of radii (a size distribution's, :func:`ndpack.pack_sizes`):
    the largest radii left go first, each where the clearance field finds room for it.

    A round takes the radii within ``SIZE_BAND`` below the largest left, and the fast choice
    capped at that largest gives the places (the tightest that fit first, moved to touch their
    nearest obstacle: :func:`_snug`). The places' radii take the list's radii, the largest to
    the largest, each the largest left that fits; those that fit nowhere wait for the next round.
    Where no prototype has room for the largest left (after the driver revived the dead ones),
    every radius larger than the largest clearance is given up: ``unplaced`` lists them.
    """

    name = "sized"
    searches = False  # its choice gives radii up itself, and returns none only when none are left

    def __init__(self, state, radii, polish_ahead=None, band: float = SIZE_BAND, ratio: float = SPLIT_RATIO):
        super().__init__(state, window=FAST_WINDOW, ratio=ratio, polish_ahead=polish_ahead)
        self.ties = False  # capped at the largest radius left: its ties are the capped ones'
        self.pending = np.sort(np.asarray(radii, dtype=np.float64))[::-1]  # largest first
        self.band = band
        self.unplaced = np.empty(0)

    def choose(self, state, min_radius, room, max_radius=np.inf):
        while len(self.pending):
            head = self.pending[0]
            size = min(room, int(np.searchsorted(-self.pending, -(1 - self.band) * head, side="right")))
            wanted = self.pending[:size]
            centers, fits = Fast.choose(self, state, min(wanted[-1], max_radius), size, min(head, max_radius))
            if len(fits) == 0:
                # No room for the largest left: give up every radius above the largest clearance.
                top = state.prototypes.top()
                lost = max(1, int(np.searchsorted(-self.pending, -(top - state.margin), side="left")))
                self.unplaced = np.concatenate([self.unplaced, self.pending[:lost]])
                self.pending = self.pending[lost:]
                continue
            radii, taken = _assign(wanted, fits)
            placed = radii > 0
            self.pending = np.concatenate([wanted[~taken], self.pending[size:]])
            return centers[placed], radii[placed]
        return np.empty((0, state.dim)), np.empty(0)

    def after_round(self, state, centers, radii, room):
        # Centres only: a sphere whose centre came out past the walls does not count; its radius
        # goes back to the list (the sphere stays, an obstacle, as in a larger bed cut by centre).
        returned = radii[~state.inside[state.count - len(radii) : state.count]]
        if len(returned):
            self.pending = np.sort(np.concatenate([self.pending, returned]))[::-1]
        super().after_round(state, centers, radii, room)


def ahead_schedule(polish_steps: np.ndarray) -> np.ndarray:
    """The polish ahead's schedule, (P,) float64: the steps of ``polish_steps`` (T,) from where
    ``eps`` has cooled to ``AHEAD_EPS_START``."""
    return polish_steps[polish_steps <= AHEAD_EPS_START]


def split_ratio(launch_bound: bool) -> float:
    """The fast mode's split ratio on a backend: ``SPLIT_RATIO_AHEAD`` where launches are bound by
    their latency (a GPU), else ``SPLIT_RATIO``."""
    return SPLIT_RATIO_AHEAD if launch_bound else SPLIT_RATIO


def _assign(wanted, fits):
    """Radii for places that fit spheres up to ``fits`` (k,), from ``wanted`` (m,), descending:
    each place (the largest fit first) gets the largest radius left that fits it. Returns the
    radii (k,) (0 where none fits) and which of ``wanted`` were taken (m,) bool."""
    radii, taken = np.zeros(len(fits)), np.zeros(len(wanted), dtype=bool)
    next_free = 0
    for place in np.argsort(-fits, kind="stable"):
        while next_free < len(wanted) and wanted[next_free] > fits[place]:
            next_free += 1  # too large here, and for every smaller place after: it waits
        if next_free == len(wanted):
            break
        radii[place], taken[next_free] = wanted[next_free], True
        next_free += 1
    return radii, taken
