"""Space-time A* for one robot among the tubes of the robots placed before it.

The fleet design (:mod:`.fleet`) first keeps a robot's way or re-times its via boxes
(:func:`~.moving.retime`); when another robot comes the other way down the same aisle, no
waiting on that way helps. This module plans the robot's path again in space *and* time:

* **The grid.** Cells of side :data:`CELL` over the body dimensions; a cell is free when
  its centre keeps :data:`STATIC_ROOM` from every obstacle of the planning spec (its
  obstacles already grown by the robot's reach, and the docks of the other robots) and
  from the state space's walls.
* **Time.** Steps of ``CELL / speed`` seconds: a move to one of the 4 neighbours takes one
  step, to a diagonal one two (both side cells free), a wait one step.
* **The placed robots.** Each placed tube's boxes over short spans, grown by both reaches
  and by :data:`ROOM` (the room the robot's own tube takes around a cell's centre), mark
  the cells whose centres they hold as taken over the steps they span (the last box
  until the end of the horizon: a parked robot). A move keeps both its cells clear over
  all its steps.
* **The search.** A* over (cell, step) with the static distance to the goal (Dijkstra on
  the free grid, ``scipy.sparse.csgraph``) as its heuristic, earliest arrival first; the
  goal cell must stay clear from the arrival to the end of the horizon; at most
  :data:`MAX_EXPANSIONS` states.
* **The tube.** The path's runs in one direction become via boxes (half-width
  :data:`~.via.VIA_HALF_WIDTH`), its waits held boxes, from ``X-hat_0`` to ``T-hat``, timed
  as the search timed them (:func:`space_time_segments`).

Nothing here is trusted: the tube so planned is accepted only when its own check
(:func:`~.search.check_tube`), its input proof and the pair certificate against every
placed tube pass (:func:`~.fleet.design_fleet`).
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from ..spec.loader import Spec
from ..tube.parameters import ReachSegment, TubeDesign
from .via import VIA_HALF_WIDTH

__all__ = ["CELL", "MAX_EXPANSIONS", "ROOM", "STATIC_ROOM", "Reservations", "SpaceTimeGrid",
           "shortcut", "space_time_path", "space_time_segments"]

#: The grid's cell side, state units (metres).
CELL = 0.5
#: The room a robot's own tube takes around a cell's centre, added to the placed robots'
#: boxes on the grid, state units (its via box's half-width, the adaptive tube around it
#: and a margin).
ROOM = 0.2
#: The room kept between a free cell's centre and the obstacles and walls, state units.
STATIC_ROOM = 0.25
#: The most (cell, step) states the search expands.
MAX_EXPANSIONS = 200_000

_MOVES = ((1, 0, 1), (-1, 0, 1), (0, 1, 1), (0, -1, 1),
          (1, 1, 2), (1, -1, 2), (-1, 1, 2), (-1, -1, 2))


@dataclass(frozen=True)
class SpaceTimeGrid:
    """The free cells of a planning spec on its body dimensions.

    Attributes
    ----------
    origin : ndarray, shape (2,)
        The centre of cell ``(0, 0)``, state units.
    cell : float
        The side of a cell.
    free : ndarray of bool, shape (nx, ny)
        The free cells (module notes).
    dims : tuple of int
        The two body dimensions.
    """

    origin: np.ndarray
    cell: float
    free: np.ndarray
    dims: tuple[int, int]

    @classmethod
    def of(cls, spec: Spec, dims: Sequence[int], cell: float = CELL) -> "SpaceTimeGrid":
        """The grid of ``spec``'s state space and obstacles on ``dims``.

        Parameters
        ----------
        spec : Spec
            The planning spec (its obstacles grown by the robot's reach).
        dims : sequence of int
            Two state dimensions.
        cell : float
            The cell side.

        Returns
        -------
        SpaceTimeGrid
        """
        d = list(dims)
        lower = np.array(spec.state_space.lower)[d]
        upper = np.array(spec.state_space.upper)[d]
        counts = np.maximum(np.floor((upper - lower) / cell).astype(int), 1)
        origin = lower + 0.5 * (upper - lower - (counts - 1) * cell)
        ii, jj = np.meshgrid(np.arange(counts[0]), np.arange(counts[1]), indexing="ij")
        centre = origin + cell * np.stack([ii, jj], axis=-1)
        reach = STATIC_ROOM
        free = np.all((centre - reach >= lower) & (centre + reach <= upper), axis=-1)
        for ob in spec.obstacle_boxes():
            lo, hi = np.array(ob.lower)[d], np.array(ob.upper)[d]
            free &= ~np.all((centre - reach < hi) & (centre + reach > lo), axis=-1)
        return cls(origin, float(cell), free, (int(d[0]), int(d[1])))

    def index(self, point: Sequence[float]) -> tuple[int, int] | None:
        """The free cell whose centre is nearest ``point`` (on the grid's dimensions),
        ``None`` when no free cell lies within one cell side of it."""
        ii, jj = np.nonzero(self.free)
        if not ii.size:
            return None
        centres = self.origin + self.cell * np.stack([ii, jj], axis=1)
        dist = np.max(np.abs(centres - np.asarray(point, dtype=float)), axis=1)
        k = int(np.argmin(dist))
        return (int(ii[k]), int(jj[k])) if dist[k] <= self.cell else None

    def centre(self, cell: tuple[int, int]) -> np.ndarray:
        """The centre of ``cell``, state units."""
        return self.origin + self.cell * np.array(cell, dtype=float)

    def steps_to(self, goal: tuple[int, int]) -> np.ndarray:
        """Steps from every cell to ``goal`` over free cells (``inf`` where cut off)."""
        nx, ny = self.free.shape
        ids = np.arange(nx * ny).reshape(nx, ny)
        rows, cols, cost = [], [], []
        for di, dj, c in _MOVES:
            a = self.free[max(0, -di):nx - max(0, di), max(0, -dj):ny - max(0, dj)]
            b = self.free[max(0, di):, max(0, dj):][:a.shape[0], :a.shape[1]]
            ok = a & b
            if di and dj:
                ok &= self.free[max(0, di):, max(0, -dj):ny - max(0, dj)][:a.shape[0], :a.shape[1]]
                ok &= self.free[max(0, -di):nx - max(0, di), max(0, dj):][:a.shape[0], :a.shape[1]]
            src = ids[max(0, -di):nx - max(0, di), max(0, -dj):ny - max(0, dj)][ok]
            dst = ids[max(0, di):, max(0, dj):][:a.shape[0], :a.shape[1]][ok]
            rows.append(src)
            cols.append(dst)
            cost.append(np.full(src.size, float(c)))
        graph = coo_matrix((np.concatenate(cost), (np.concatenate(rows), np.concatenate(cols))),
                           shape=(nx * ny, nx * ny)).tocsr()
        dist = dijkstra(graph, directed=True, indices=int(ids[goal]), min_only=True)
        # distances *from* the goal on a symmetric graph are distances *to* it
        return dist.reshape(nx, ny)


class Reservations:
    """The cells the placed robots' tubes take at each step (module notes).

    Parameters
    ----------
    grid : SpaceTimeGrid
    step : float
        Seconds per step.
    steps : int
        The horizon in steps; boxes that last to ``inf`` take their cells to it.
    """

    def __init__(self, grid: SpaceTimeGrid, step: float, steps: int):
        self.grid, self.step, self.steps = grid, float(step), int(steps)
        self.taken = np.zeros((self.steps + 1,) + grid.free.shape, dtype=bool)

    def add(self, t_start: np.ndarray, t_end: np.ndarray, lower: np.ndarray,
            upper: np.ndarray) -> None:
        """Mark the cells that boxes ``[lower[k], upper[k]]`` (on the grid's dimensions,
        already grown by both reaches) meet over ``[t_start[k], t_end[k]]``, grown by
        :data:`ROOM` and the cell's own extent.

        Parameters
        ----------
        t_start, t_end : ndarray, shape (K,)
            Seconds (``t_end`` may be ``inf``).
        lower, upper : ndarray, shape (K, 2)
        """
        g = self.grid
        reach = ROOM
        shape = np.array(g.free.shape)
        lo_i = np.ceil((lower - reach - g.origin) / g.cell - 1e-9).astype(int)
        hi_i = np.floor((upper + reach - g.origin) / g.cell + 1e-9).astype(int)
        lo_i, hi_i = np.maximum(lo_i, 0), np.minimum(hi_i, shape - 1)
        k0 = np.floor(t_start / self.step).astype(int)
        with np.errstate(invalid="ignore"):
            k1 = np.where(np.isfinite(t_end), np.ceil(t_end / self.step), self.steps)
        k1 = np.minimum(k1.astype(int), self.steps)
        for a, b, (i0, j0), (i1, j1) in zip(k0, k1, lo_i, hi_i):
            if a <= self.steps and i0 <= i1 and j0 <= j1:
                self.taken[a:b + 1, i0:i1 + 1, j0:j1 + 1] = True


def space_time_path(grid: SpaceTimeGrid, taken: Reservations, start: tuple[int, int] | None,
                    goal: tuple[int, int] | None, last_step: int,
                    max_expansions: int = MAX_EXPANSIONS,
                    stay_steps: int | None = None) -> list[tuple[int, int, int]] | None:
    """The earliest path from ``start`` at step 0 to ``goal`` by ``last_step`` that keeps
    clear of the taken cells, the goal clear from the arrival on (for ``stay_steps``
    steps, or to the horizon). A diagonal move needs both cells beside it free and not
    taken over its steps (the tube's box sweeps their corners).

    Parameters
    ----------
    grid : SpaceTimeGrid
    taken : Reservations
    start, goal : (int, int) or None
        Cells (:meth:`SpaceTimeGrid.index`; ``None``: no path).
    last_step : int
        The latest arrival (the prescribed time in steps).
    max_expansions : int
        The search's budget.
    stay_steps : int, optional
        How many steps the goal must stay clear after the arrival; default: to the
        horizon.

    Returns
    -------
    list of (i, j, step) or None
        From ``(start, 0)`` to ``(goal, arrival)``, one entry per move or wait (a wait
        repeats the cell one step later; a diagonal move takes two steps); ``None`` when no
        path is found within the budget.

    Examples
    --------
    >>> import numpy as np
    >>> grid = SpaceTimeGrid(np.zeros(2), 1.0, np.ones((5, 3), dtype=bool), (0, 1))
    >>> taken = Reservations(grid, 1.0, 10)
    >>> [c[:2] for c in space_time_path(grid, taken, (0, 1), (4, 1), 10)]
    [(0, 1), (1, 1), (2, 1), (3, 1), (4, 1)]
    """
    busy = taken.taken
    horizon = taken.steps
    if start is None or goal is None or not (grid.free[start] and grid.free[goal]):
        return None
    # the goal, once reached at step k, must stay clear to the horizon (or stay_steps on)
    at_goal = busy[:, goal[0], goal[1]]
    if stay_steps is None:
        clear_after = np.flip(np.cumsum(np.flip(at_goal))) == 0
    else:
        ahead = np.concatenate([np.cumsum(at_goal[::-1])[::-1], [0]])
        ends = np.minimum(np.arange(at_goal.size) + stay_steps + 1, at_goal.size)
        clear_after = ahead[:at_goal.size] - ahead[ends] == 0
    h = grid.steps_to(goal)
    if not np.isfinite(h[start]):
        return None
    nx, ny = grid.free.shape
    n = nx * ny
    # Flat bytes, read a few times per move (an element of ``bytes`` is read in a fraction
    # of numpy's indexing): the cell ``c`` of step ``q`` is ``q * n + c``; ``over[cost]``
    # says whether the cell is taken at a step of ``k .. k + cost`` (up to the horizon).
    ahead = np.concatenate([busy[1:], busy[-1:]])
    over1 = busy | ahead
    over = {1: over1[:-1].tobytes(),
            2: (over1 | np.concatenate([ahead[1:], busy[-1:]]))[:-1].tobytes()}
    seen = bytearray(busy.size)
    parent: dict[tuple[int, int, int], tuple[int, int, int]] = {}
    heap = [(float(h[start]), 0, start[0], start[1])]
    expansions = 0
    cells = busy.tobytes()
    free = grid.free.ravel().tolist()
    steps_to = h.ravel().tolist()

    while heap and expansions < max_expansions:
        _, k, i, j = heapq.heappop(heap)
        here = i * ny + j
        if seen[k * n + here]:
            continue
        seen[k * n + here] = True
        expansions += 1
        if (i, j) == goal and clear_after[k]:
            path = [(i, j, k)]
            while path[-1] in parent:
                path.append(parent[path[-1]])
            return list(reversed(path))
        if k >= min(last_step, horizon):
            continue
        if not cells[(k + 1) * n + here] and not seen[(k + 1) * n + here]:
            parent[(i, j, k + 1)] = (i, j, k)
            heapq.heappush(heap, (k + 1 + steps_to[here], k + 1, i, j))
        for di, dj, cost in _MOVES:
            a, b, kk = i + di, j + dj, k + cost
            there = a * ny + b
            if not (0 <= a < nx and 0 <= b < ny) or kk > last_step or not free[there]:
                continue
            if cost == 2 and not (free[here + di * ny] and free[here + dj]):
                continue
            key = (a, b, kk)
            if seen[kk * n + there] or key in parent:
                continue
            span = over[cost]
            if span[k * n + here] or span[k * n + there]:
                continue
            # nor a diagonal past a taken cell's corner (as past an obstacle's, above)
            if cost == 2 and (span[k * n + here + di * ny] or span[k * n + here + dj]):
                continue
            parent[key] = (i, j, k)
            heapq.heappush(heap, (kk + steps_to[there], kk, a, b))
    return None


def shortcut(path: Sequence[tuple[int, int, int]], grid: SpaceTimeGrid,
             taken: Reservations) -> list[tuple[int, int, int]]:
    """``path`` with its entries joined by straight moves where they keep clear: from each
    kept entry, the farthest later one whose straight line, timed as a smooth-step
    segment (``p = tau^3 (10 - 15 tau + 6 tau^2)`` of the way at the share ``tau`` of its
    time), passes only cells that are free and not taken at each step and the next (both
    neighbours where it lies between two).

    Parameters
    ----------
    path : sequence of (i, j, step)
        From :func:`space_time_path`.
    grid : SpaceTimeGrid
    taken : Reservations

    Returns
    -------
    list of (i, j, step)
        A sub-sequence of ``path`` with the same first and last entries; consecutive
        entries need not be neighbours (a move may be slower than one cell per step, or
        a wait and a move in one).

    Examples
    --------
    A move, a wait and a move along one row become one slower move:

    >>> import numpy as np
    >>> grid = SpaceTimeGrid(np.zeros(2), 1.0, np.ones((5, 3), dtype=bool), (0, 1))
    >>> taken = Reservations(grid, 1.0, 10)
    >>> shortcut([(0, 1, 0), (1, 1, 1), (1, 1, 2), (2, 1, 3)], grid, taken)
    [(0, 1, 0), (2, 1, 3)]
    """
    busy, free = taken.taken, grid.free
    last = busy.shape[0] - 1

    def clear(a: tuple[int, int, int], b: tuple[int, int, int]) -> bool:
        for k in range(a[2], b[2] + 1):
            tau = (k - a[2]) / (b[2] - a[2])
            share = tau ** 3 * (10.0 - 15.0 * tau + 6.0 * tau * tau)
            at = np.array(a[:2], dtype=float) + share * np.subtract(b[:2], a[:2])
            lo, hi = np.floor(at + 1e-9).astype(int), np.ceil(at - 1e-9).astype(int)
            for i in range(lo[0], hi[0] + 1):
                for j in range(lo[1], hi[1] + 1):
                    if not free[i, j] or busy[k, i, j] or busy[min(k + 1, last), i, j]:
                        return False
        return True

    out = [tuple(path[0])]
    a = 0
    while a < len(path) - 1:
        b = len(path) - 1
        while b > a + 1 and not clear(path[a], path[b]):
            b -= 1
        out.append(tuple(path[b]))
        a = b
    return out


def space_time_segments(path: Sequence[tuple[int, int, int]], grid: SpaceTimeGrid,
                        base: TubeDesign, step: float, profile: str
                        ) -> tuple[ReachSegment, ...]:
    """The reach segments of a space-time path: ``X-hat_0`` to the first via box, the
    runs of moves in one direction, the waits held, the last via box to ``T-hat``.

    Parameters
    ----------
    path : sequence of (i, j, step)
        From :func:`space_time_path`.
    grid : SpaceTimeGrid
    base : TubeDesign
        Its ``X-hat_0`` and ``T-hat`` (first and last reach boxes), its dimension.
    step : float
        Seconds per step.
    profile : str
        The moves' profile (``"smoothstep"`` or ``"cruise"``).

    Returns
    -------
    tuple of ReachSegment
        Contiguous in time from ``t = 0``; a wait is a segment whose box does not change.
    """
    d = list(grid.dims)
    x0 = np.array(base.initial_state, dtype=float)

    def box(cell) -> tuple[tuple[float, ...], tuple[float, ...]]:
        c = x0.copy()
        c[d] = grid.centre(cell)
        lo = c - VIA_HALF_WIDTH
        hi = c + VIA_HALF_WIDTH
        return tuple(float(v) for v in lo), tuple(float(v) for v in hi)

    # knots: where the path turns, starts or ends a wait (cell, step)
    knots = [path[0]]
    for prev, cur, nxt in zip(path, path[1:], path[2:]):
        if (cur[0] - prev[0], cur[1] - prev[1]) != (nxt[0] - cur[0], nxt[1] - cur[1]):
            knots.append(cur)
    knots.append(path[-1])
    boxes = [(tuple(base.initial_lower), tuple(base.initial_upper))]
    boxes += [box(c[:2]) for c in knots[1:-1]]
    boxes.append((tuple(base.target_lower), tuple(base.target_upper)))
    times = [0.0] + [c[2] * step for c in knots[1:]]
    out = []
    for k in range(len(times) - 1):
        (a_lo, a_hi), (b_lo, b_hi) = boxes[k], boxes[k + 1]
        if knots[k][:2] == knots[k + 1][:2] and 0 < k < len(knots) - 2:
            b_lo, b_hi = a_lo, a_hi                       # a wait holds its box
        out.append(ReachSegment(times[k], times[k + 1], a_lo, a_hi, b_lo, b_hi, profile))
    return tuple(out)
