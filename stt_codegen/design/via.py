"""Via-point reach tubes: a piecewise reach tube through the free space (beyond the paper).

When the paper's single straight reach tube (eq. (4)) with one circumvent per obstacle
has no certified design, the reach box can instead move through a short sequence of via
boxes ``B_0 = X-hat_0, B_1, ..., B_m = T-hat`` (docs/decisions.md, decision 12):

* **Free boxes.** The state space is cut into a grid of cells of side ``h`` in the
  dimensions some obstacle restricts (the others interpolate from ``X-hat_0`` to
  ``T-hat``); a cell's via box is centred in it with half-width ``d_v`` (at most the
  initial and target half-widths and :data:`VIA_HALF_WIDTH`).
* **Moves.** Segment ``k`` moves every bound from ``B_k`` to ``B_{k+1}`` by the same
  smooth step ``sigma(tau)`` in ``[0, 1]`` (``"smoothstep"``), so each intermediate box
  lies inside the bounding box of ``B_k`` and ``B_{k+1}``. A move is allowed when that
  bounding box, widened by :data:`VIA_MARGIN`, misses every obstacle: the segment then
  needs no circumvent.
* **Path.** Dijkstra over the moves between neighbouring cells (``scipy.sparse.csgraph``,
  weights the centre distance; the same input gives the same path), then shortened
  greedily: from each via box, the farthest later box on the path it can move to
  directly.
* **Timing.** Durations in proportion to the centre distance (max norm), the last
  segment ending at ``t_c`` in the target box (``"length"``: every segment at the same
  peak rate, what bounds a velocity input); or, ``spec.tube.via_timing =
  "acceleration"``, in proportion to its square root (every segment at the same peak
  acceleration, what bounds a force: :data:`ACCELERATION_TIMING`). The profile has zero
  slope at every via point, so ``rho`` and ``rho_dot`` are continuous there.

The tube is then certified like any other (:func:`~stt_codegen.design.certificate.certify_tube`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from itertools import product

import numpy as np

from ..errors import DesignError
from ..spec.loader import Spec
from .failures import FailureKind
from ..tube.parameters import (CRUISE, GLIDE, SCURVE, SMOOTHSTEP, ReachSegment, TubeDesign,
                               peak_acceleration_factor, peak_rate_factor)

__all__ = ["ACCELERATION_PROFILES", "ACCELERATION_TIMING", "BLEND_CORNERS", "BLEND_SHARES",
           "CORNER_SHIFTS", "LENGTH_TIMING", "OVERLAP_SAMPLES", "STOP_CORNERS", "TURN_TIMING",
           "VIA_CORNERS", "VIA_HALF_WIDTH", "VIA_MARGIN", "VIA_TIMINGS", "ViaPlan", "blend_plan",
           "blended_times", "move_weight", "plan_via", "timed_moves", "via_design"]

#: Largest half-width of a via box, state units.
VIA_HALF_WIDTH = 0.1
#: Clearance kept between a move's bounding box and every obstacle, state units.
VIA_MARGIN = 0.05
#: Most grid cells (the cell side grows until the grid fits).
MAX_CELLS = 6000
#: Via timing: each move's duration in proportion to its length (max norm). A profile's
#: peak rate is then the same on every move: the timing for a velocity input (law (13)).
LENGTH_TIMING = "length"
#: Via timing: each move's duration in proportion to the square root of its length. A
#: profile's peak acceleration (``4.76 D / T^2`` for the S-curve it is used with, ``5.77 D /
#: T^2`` for the quintic smooth step) is then the same on every move: the timing for a force
#: input (the cascade, docs/second-order.md).
ACCELERATION_TIMING = "acceleration"
#: Via timing: each move's duration in proportion to its length plus ``tube.via_turn``
#: times its turn from the move before (radians between their directions on the first two
#: dimensions): for a base, ``v_max / omega_max``, so a move after a corner has the time
#: to turn too (docs/differential-drive.md).
TURN_TIMING = "turn"
VIA_TIMINGS = (LENGTH_TIMING, ACCELERATION_TIMING, TURN_TIMING)
#: Via corners: every segment starts when the previous one ends, so the tube stops at
#: every via box (``rho_dot = 0`` there).
STOP_CORNERS = "stop"
#: Via corners: a segment starts before the previous one ends, by a share of the shorter
#: of the two (:data:`BLEND_SHARES`), where the box's sweep over that overlap keeps
#: :data:`VIA_MARGIN` from every obstacle; the tube passes the via box without stopping
#: (:func:`blended_times`).
BLEND_CORNERS = "blend"
VIA_CORNERS = (STOP_CORNERS, BLEND_CORNERS)
#: Shares of the shorter of two consecutive moves during which both may move the box, at
#: a blended corner, largest first (:func:`blended_times` takes the largest whose sweep is
#: free). At most 1/2, so that no three segments move the box at once.
BLEND_SHARES = (0.5, 0.25, 0.125)
#: The profiles a move timed for the acceleration may take, least peak acceleration first
#: (peak accelerations 4.76, 5.38, 5.77 and 9.38, peak rates 2, 5/3, 15/8 and 1.25 times the
#: mean): from the spec's ``tube.via_profile`` on. The glide's are both below the smooth
#: step's, so a move of a plan from ``"scurve"`` on never takes the smooth step; a plan from
#: ``"smoothstep"`` on takes neither the S-curve nor the glide.
ACCELERATION_PROFILES = (SCURVE, GLIDE, SMOOTHSTEP, CRUISE)


def move_weight(length: float, timing: str, turn: float = 0.0) -> float:
    """A move's share of time before normalisation: its duration is this over the sum of
    its plan's (or leg's) weights times the time the plan has.

    Parameters
    ----------
    length : float
        The move's centre distance, state units: in the max norm (a bound per axis), in
        the Euclidean norm with :data:`TURN_TIMING` (a base's speed).
    timing : {"length", "acceleration", "turn"}
        :data:`LENGTH_TIMING` (``length``), :data:`ACCELERATION_TIMING`
        (``sqrt(length)``) or :data:`TURN_TIMING` (``length + turn``).
    turn : float
        With :data:`TURN_TIMING`: the move's turn from the move before, in state units
        (radians times ``tube.via_turn``).

    Returns
    -------
    float

    Raises
    ------
    ValueError
        An unknown timing.
    """
    if timing == LENGTH_TIMING:
        return length
    if timing == ACCELERATION_TIMING:
        return math.sqrt(length)
    if timing == TURN_TIMING:
        return length + turn
    raise ValueError(f"unknown via timing {timing!r}: one of {', '.join(VIA_TIMINGS)}")


def _turn(before: np.ndarray, after: np.ndarray) -> float:
    """Radians between two moves' directions on the first two dimensions (0 where either
    has no length there)."""
    if before.size < 2 or not (np.any(before[:2]) and np.any(after[:2])):
        return 0.0
    angle = math.atan2(after[1], after[0]) - math.atan2(before[1], before[0])
    return abs(math.remainder(angle, 2.0 * math.pi))


def timed_moves(spec: Spec, moves: list[np.ndarray], duration: float, profile: str
                ) -> tuple[list[float], list[str]]:
    """The moves' durations sharing ``duration``, and each move's profile.

    With the length or the turn timing, or without ``state_space.velocity_bound``, each
    move's share is its :func:`move_weight` over their sum (with the turn timing, its
    Euclidean length and its turn from the move before times ``tube.via_turn``: the time
    to drive it at ``v_max`` and to turn into it at ``omega_max``, over ``v_max``) and
    every move has ``profile``. Timed for the
    acceleration (:data:`ACCELERATION_TIMING`) under a velocity bound ``v``, the moves get
    the least common peak acceleration ``a`` that fits: move ``k`` (largest coordinate move
    ``L_k``, ``M_k = max_i |m_i| / v_i``) lasts ``min_p max(sqrt(c_p L_k / a), r_p M_k)``
    over the profiles ``p`` of :data:`ACCELERATION_PROFILES` from ``profile`` on (peak
    acceleration ``c_p L / D^2``, peak rate ``r_p L / D``): the profile of least peak
    acceleration whose peak rate stays within the bound (the certificate then proves
    ``|x2_i| <= v_i`` with the position stage's correction on top), and a bisection on
    ``a`` makes the durations sum to ``duration``. Where the bound cannot be kept at all
    (the profile of least peak rate needs more than ``duration``), every move has that
    profile, in proportion to ``M_k``.

    Parameters
    ----------
    spec : Spec
        Its ``tube.via_timing`` and
        :attr:`~stt_codegen.spec.loader.Spec.velocity_bound`.
    moves : list of ndarray, shape (n,) each
        The moves' centre displacements, state units.
    duration : float
        Seconds the moves share.
    profile : str
        The moves' profile where the bound does not choose it.

    Returns
    -------
    durations : list of float
        Seconds, one per move, summing to ``duration`` (to rounding).
    profiles : list of str
        One per move.
    """
    timing = spec.tube.via_timing
    # a base's time (the turn timing) goes by its speed, the Euclidean distance; the other
    # timings' by the per-axis bound, the max norm
    lengths = [float(np.linalg.norm(m)) if timing == TURN_TIMING else float(np.max(np.abs(m)))
               for m in moves]
    turns = [0.0] + [spec.tube.via_turn * _turn(a, b) for a, b in zip(moves, moves[1:])]
    weights = [move_weight(length, timing, turn) for length, turn in zip(lengths, turns)]
    if (timing != ACCELERATION_TIMING or spec.velocity_bound is None or not moves
            or not any(weights)):            # (moves of no length: equal shares)
        total = sum(weights)
        return ([(w / total if total > 0 else 1.0 / len(moves)) * duration for w in weights],
                [profile] * len(moves))
    reach = np.asarray(spec.velocity_bound, dtype=float)
    ratios = [float(np.max(np.abs(m) / reach)) for m in moves]
    tried = (ACCELERATION_PROFILES[ACCELERATION_PROFILES.index(profile):]
             if profile in ACCELERATION_PROFILES else (profile,))
    shapes = [(peak_acceleration_factor(p), peak_rate_factor(p), p) for p in tried]

    def at(accel: float) -> tuple[list[float], list[str]]:
        out = [min((max(math.sqrt(c * length / accel), r * ratio), p) for c, r, p in shapes)
               for length, ratio in zip(lengths, ratios)]
        return [d for d, _ in out], [p for _, p in out]

    slowest, last = min((r, p) for _, r, p in shapes)
    if slowest * sum(ratios) >= duration:
        total = sum(ratios)
        return [q / total * duration for q in ratios], [last] * len(moves)
    low, high = 1e-12, 1.0
    while sum(at(high)[0]) > duration:
        low, high = high, high * 4.0
    for _ in range(200):
        mid = math.sqrt(low * high)
        if sum(at(mid)[0]) > duration:
            low = mid
        else:
            high = mid
    durations, profiles = at(high)
    scale = duration / sum(durations)
    return [d * scale for d in durations], profiles


@dataclass(frozen=True)
class ViaPlan:
    """The via boxes of a piecewise reach tube.

    Attributes
    ----------
    lower, upper : tuple of tuple of float
        Box corners ``B_0 .. B_m``, shape (m + 1, n).
    times : tuple of float
        ``t_0 = 0 < t_1 < ... < t_m <= t_c``, seconds: move ``k`` ends at ``t_{k+1}``; with
        stopped corners the tube is in ``B_k`` at ``t_k``.
    profiles : tuple of str
        Each move's profile where :func:`timed_moves` chose it (``m`` entries), else empty.
    starts : tuple of float
        With blended corners (:data:`BLEND_CORNERS`), when each move starts (``m``
        entries, ``starts[k] <= t_k``); empty: move ``k`` starts at ``t_k``.
    """

    lower: tuple[tuple[float, ...], ...]
    upper: tuple[tuple[float, ...], ...]
    times: tuple[float, ...]
    profiles: tuple[str, ...] = ()
    starts: tuple[float, ...] = ()

    def segments(self, profile: str = SMOOTHSTEP) -> tuple[ReachSegment, ...]:
        """The reach segments between consecutive via boxes.

        Parameters
        ----------
        profile : {"smoothstep", "cruise", "scurve"}
            Their profile (each has zero slope at every via point), where the plan has not
            chosen each move's (:attr:`profiles`).

        Returns
        -------
        tuple of ReachSegment
        """
        starts = self.starts or self.times[:-1]
        return tuple(ReachSegment(starts[k], self.times[k + 1], self.lower[k],
                                  self.upper[k], self.lower[k + 1], self.upper[k + 1],
                                  self.profiles[k] if self.profiles else profile)
                     for k in range(len(self.times) - 1))


def _meets(lower: np.ndarray, upper: np.ndarray, obstacles: np.ndarray,
           margin: float) -> np.ndarray:
    """(K, B): box k, widened by ``margin``, meets obstacle box b (touching does not count)."""
    lo, hi = lower - margin, upper + margin
    out = np.ones((lower.shape[0], obstacles.shape[0]), dtype=bool)
    # one column of one obstacle at a time: (K,) temporaries instead of (K, B, n) ones
    for b in range(obstacles.shape[0]):
        for i in range(lower.shape[1]):
            out[:, b] &= (lo[:, i] < obstacles[b, 1, i]) & (hi[:, i] > obstacles[b, 0, i])
    return out


def _free(lower: np.ndarray, upper: np.ndarray, obstacles: np.ndarray,
          space: tuple[np.ndarray, np.ndarray], margin: float = VIA_MARGIN) -> np.ndarray:
    """Boxes (K, n) that lie in the state space and keep ``margin`` from every obstacle."""
    return _free_columns(list(lower.T), list(upper.T), obstacles, space, margin)


def _free_columns(lower: list, upper: list, obstacles: np.ndarray, space,
                  margin: float) -> np.ndarray:
    """:func:`_free` of boxes given by the columns of their corners (n arrays (K,) each).

    The comparisons of :func:`_meets`, one column at a time into one (K,) mask: gathers of
    rows and reductions over the short axis of (K, n) or (K, B) arrays cost more than the
    comparisons themselves.
    """
    inside = lower[0] >= space[0][0]
    inside &= upper[0] <= space[1][0]
    for i in range(1, len(lower)):
        inside &= lower[i] >= space[0][i]
        inside &= upper[i] <= space[1][i]
    lo = [c - margin for c in lower]
    hi = [c + margin for c in upper]
    for b in range(obstacles.shape[0]):
        met = (lo[0] < obstacles[b, 1, 0]) & (hi[0] > obstacles[b, 0, 0])
        for i in range(1, len(lower)):
            met &= lo[i] < obstacles[b, 1, i]
            met &= hi[i] > obstacles[b, 0, i]
        inside &= ~met
    return inside


def _largest(columns: list) -> np.ndarray:
    """The element-wise largest of the arrays ``columns`` (the max over a short axis,
    without the reduction's cost)."""
    out = columns[0]
    for column in columns[1:]:
        out = np.maximum(out, column)
    return out


def _max_distance(centres: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``max_i |centres[a, i] - centres[b, i]|`` (M,), the moves' lengths (max norm)."""
    return _largest([np.abs(c[a] - c[b]) for c in np.ascontiguousarray(centres.T)])


def plan_via(spec: Spec, base: TubeDesign) -> ViaPlan:
    """Via boxes from ``X-hat_0`` to ``T-hat`` through the free space (see the module notes).

    Parameters
    ----------
    spec : Spec
        State space and obstacles.
    base : TubeDesign
        Its first and last reach boxes are ``X-hat_0`` and ``T-hat``.

    Returns
    -------
    ViaPlan

    Raises
    ------
    DesignError
        No chain of free moves joins the two boxes (kind ``NO_PASSAGE``); the message
        says where the free passage reachable from ``x(0)`` comes closest to the target.
        Where not even a point can pass (kind ``WALLED_OFF``), it names the obstacles
        that wall off the target (or the start) instead.
    """
    n = base.dimension
    space = (np.array(spec.state_space.lower), np.array(spec.state_space.upper))
    boxes = spec.obstacle_boxes()
    obstacles = np.array([[b.lower, b.upper] for b in boxes]).reshape(-1, 2, n)
    start_lo, start_hi = np.array(base.initial_lower), np.array(base.initial_upper)
    goal_lo, goal_hi = np.array(base.target_lower), np.array(base.target_upper)
    grid_dims = [i for i in range(n) if any(b.lower[i] > space[0][i] or b.upper[i] < space[1][i]
                                            for b in boxes)] or [0]
    half = min([VIA_HALF_WIDTH] + [0.5 * (start_hi[i] - start_lo[i]) for i in grid_dims]
               + [0.5 * (goal_hi[i] - goal_lo[i]) for i in grid_dims])
    extent = space[1] - space[0]
    step = half
    while math.prod(int(extent[i] / step) for i in grid_dims) > MAX_CELLS:
        step *= 1.25
    counts = [max(int(extent[i] / step), 1) for i in grid_dims]
    lows, highs = _grid_nodes(space, grid_dims, counts, (start_lo, start_hi),
                              (goal_lo, goal_hi), half)
    a, b, ok = _moves(lows, highs, counts, obstacles, space, VIA_MARGIN)
    a, b = a[ok], b[ok]
    mids = 0.5 * (lows + highs)
    path, dist = _shortest_path(len(lows), a, b, _max_distance(mids, a, b))
    if path is None:
        walled = _walled_off(spec, space, grid_dims, counts, obstacles)
        if walled:
            raise DesignError(f"no via-point path: {walled}", kind=FailureKind.WALLED_OFF)
        goal_centre = 0.5 * (goal_lo + goal_hi)
        reach = np.flatnonzero(np.isfinite(dist))
        near = int(reach[np.argmin(np.max(np.abs(mids[reach] - goal_centre), axis=1))])
        where = ", ".join(f"{v:.2f}" for v in mids[near])
        raise DesignError(
            f"no via-point path: the free passage reachable from x(0) (via boxes of "
            f"half-width {half:g} with {VIA_MARGIN:g} clearance) comes closest to the target "
            f"at ({where}); the passage is too narrow there", kind=FailureKind.NO_PASSAGE)
    nodes = {k: (lows[k], highs[k]) for k in path}
    path = _shortcut(path, nodes, obstacles, space)
    return _timed(path, nodes, base.prescribed_time, spec)


def _grid_nodes(space, grid_dims: list[int], counts: list[int], start, goal,
                half: float) -> tuple[np.ndarray, np.ndarray]:
    """Boxes of the graph's nodes, lower and upper corners (2 + K, n): node 0 is the start
    box, node 1 the target box, node 2 + q the via box of grid cell q (C order)."""
    (start_lo, start_hi), (goal_lo, goal_hi) = start, goal
    extent = space[1] - space[0]
    cells = np.indices(counts).reshape(len(grid_dims), -1).T        # (K, g), C order
    start_centre = 0.5 * (start_lo + start_hi)
    goal_centre = 0.5 * (goal_lo + goal_hi)
    centre = np.tile(0.5 * (start_centre + goal_centre), (len(cells), 1))
    for g, i in enumerate(grid_dims):
        centre[:, i] = space[0][i] + (cells[:, g] + 0.5) * extent[i] / counts[g]
    # the other dimensions progress with the share of the way done in the grid ones
    d0 = _largest([np.abs(centre[:, i] - start_centre[i]) for i in grid_dims])
    d1 = _largest([np.abs(goal_centre[i] - centre[:, i]) for i in grid_dims])
    fraction = np.where(d0 + d1 > 0, d0 / np.maximum(d0 + d1, 1e-300), 0.5)
    lows = start_lo + (goal_lo - start_lo) * fraction[:, None]
    highs = start_hi + (goal_hi - start_hi) * fraction[:, None]
    lows[:, grid_dims] = centre[:, grid_dims] - half
    highs[:, grid_dims] = centre[:, grid_dims] + half
    return np.vstack([start_lo, goal_lo, lows]), np.vstack([start_hi, goal_hi, highs])


def _moves(lows: np.ndarray, highs: np.ndarray, counts: list[int], obstacles: np.ndarray,
           space, margin: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Candidate moves ``a[q] -- b[q]`` between free nodes (neighbouring cells, and the
    start and target boxes to every cell and to each other), shape (M,) each, and which are
    free: the bounding box of the two boxes, widened by ``margin``, misses every obstacle."""
    low_columns = list(np.ascontiguousarray(lows.T))
    high_columns = list(np.ascontiguousarray(highs.T))
    free = _free_columns(low_columns, high_columns, obstacles, space, margin)
    free[:2] = True   # the spec's own boxes (checked by the loader and the certificate)
    flat = np.arange(len(lows) - 2).reshape(counts) + 2
    first, second = [], []
    for o in product((-1, 0, 1), repeat=len(counts)):
        if not any(o) or o < (0,) * len(o):
            continue       # each neighbour pair once
        src = tuple(slice(max(0, -d), c - max(0, d)) for d, c in zip(o, counts))
        dst = tuple(slice(max(0, d), c - max(0, -d)) for d, c in zip(o, counts))
        first.append(flat[src].ravel())
        second.append(flat[dst].ravel())
    cell_ids = np.flatnonzero(free[2:]) + 2
    first += [np.zeros_like(cell_ids), np.ones_like(cell_ids), np.array([0])]
    second += [cell_ids, cell_ids, np.array([1])]
    a, b = np.concatenate(first), np.concatenate(second)
    both = free[a] & free[b]
    a, b = a[both], b[both]
    return a, b, _free_columns([np.minimum(c[a], c[b]) for c in low_columns],
                               [np.maximum(c[a], c[b]) for c in high_columns],
                               obstacles, space, margin)


def _walled_off(spec: Spec, space, grid_dims: list[int], counts: list[int],
                obstacles: np.ndarray) -> str:
    """Why no path of any width joins ``x(0)`` and the target centre ("" if one does).

    The same grid as the via boxes, with points instead of boxes and no clearance: when
    even a point cannot move from ``x(0)`` to the target centre, the smaller of their two
    connected regions is walled off; the obstacles met by the moves out of it wall it.
    """
    from scipy.sparse import csgraph, csr_matrix   # on first use: paper designs never load it
    x0, eta = np.array(spec.initial_state), np.array(spec.target_center)
    lows, highs = _grid_nodes(space, grid_dims, counts, (x0, x0), (eta, eta), 0.0)
    a, b, ok = _moves(lows, highs, counts, obstacles, space, 0.0)
    graph = csr_matrix((np.ones(int(ok.sum())), (a[ok], b[ok])),
                       shape=(len(lows), len(lows)))
    _, labels = csgraph.connected_components(graph, directed=False)
    if labels[0] == labels[1]:
        return ""
    target_side = np.sum(labels == labels[1]) <= np.sum(labels == labels[0])
    inner = labels == labels[1 if target_side else 0]
    # every neighbour move out of the walled-off region meets an obstacle (or leaves X)
    step = np.array([(space[1][i] - space[0][i]) / c for i, c in zip(grid_dims, counts)])
    nodes = np.flatnonzero(inner)
    grid = np.array(np.unravel_index(nodes[nodes >= 2] - 2, counts)).reshape(len(counts), -1).T
    around_lo, around_hi = lows[nodes].copy(), highs[nodes].copy()
    around_lo[:, grid_dims] -= 1.5 * step
    around_hi[:, grid_dims] += 1.5 * step
    met = _meets(around_lo, around_hi, obstacles, 0.0).any(axis=0)
    names = sorted({spec.obstacles[k].source for k in np.flatnonzero(met)})
    border = bool(np.any((grid == 0) | (grid == np.array(counts) - 1)))
    what = "the target is walled off from x(0)" if target_side else \
        "x(0) is walled off from the target"
    return (f"{what} by obstacle{'s' if len(names) > 1 else ''} "
            f"{', '.join(map(str, names))}" + (" and the state-space boundary" if border
                                              else "")
            + ": no path joins x(0) and the target centre through gaps at least one via-grid "
            f"cell ({float(step.max()):.3g}) wide")


def _shortest_path(count: int, a: np.ndarray, b: np.ndarray,
                   length: np.ndarray) -> tuple[list[int] | None, np.ndarray]:
    """Dijkstra over the undirected moves ``a[q] -- b[q]`` from node 0 (start box) to node 1
    (target box): the path (``None`` without one) and the distances from node 0 (``inf``
    where unreachable)."""
    from scipy.sparse import csgraph, csr_matrix
    # csgraph reads an explicit zero of a sparse matrix as an edge (a zero-length move);
    # the pairs are distinct, so nothing is summed
    graph = csr_matrix((length, (a, b)), shape=(count, count))
    dist, before = csgraph.dijkstra(graph, directed=False, indices=0, return_predecessors=True)
    if not np.isfinite(dist[1]):
        return None, dist
    path = [1]
    while path[-1] != 0:
        path.append(int(before[path[-1]]))
    return path[::-1], dist


def _shortcut(path: list, nodes: dict, obstacles: np.ndarray, space) -> list:
    """Greedy shortening: from each box, the farthest later box it can move to directly."""
    out = [path[0]]
    k = 0
    # the boxes' corners along the path, one column per dimension
    path_lows = list(np.array([nodes[q][0] for q in path]).T)
    path_highs = list(np.array([nodes[q][1] for q in path]).T)
    while k < len(path) - 1:
        lows = [np.minimum(c[k], c[k + 1:]) for c in path_lows]
        highs = [np.maximum(c[k], c[k + 1:]) for c in path_highs]
        ok = _free_columns(lows, highs, obstacles, space, VIA_MARGIN)
        ok[0] = True   # the path's own edge
        k = k + 1 + int(np.flatnonzero(ok)[-1])
        out.append(path[k])
    return out


def _timed(path: list, nodes: dict, prescribed_time: float, spec: Spec) -> ViaPlan:
    lower = tuple(tuple(float(v) for v in nodes[k][0]) for k in path)
    upper = tuple(tuple(float(v) for v in nodes[k][1]) for k in path)
    return blend_plan(_stopped_plan(lower, upper, prescribed_time, spec), spec)


def blend_plan(plan: ViaPlan, spec: Spec, profile: str | None = None) -> ViaPlan:
    """``plan`` with its corners blended where ``spec.tube.via_corners`` asks it, over the
    same time ``[plan.times[0], plan.times[-1]]``.

    The via boxes of corners that cannot be blended by the largest share are moved away
    from the obstacles first (:func:`_roomier_corners`); then :func:`blended_times`. The
    moves then last longer than the stopped plan's (the overlaps share the time), so the
    plan is timed again (:func:`timed_moves`, each move's profile chosen for its own
    duration) for that much time, blended again, and scaled back into the plan's time.

    Parameters
    ----------
    plan : ViaPlan
        Stopped corners, timed by :func:`timed_moves` over its time.
    spec : Spec
        Its ``tube.via_corners``, obstacles, state space and timing.
    profile : str, optional
        The moves' profile where the plan has not chosen each one's; default
        ``spec.tube.via_profile``.

    Returns
    -------
    ViaPlan
        ``plan`` itself with ``"stop"`` or fewer than two moves; else with ``starts``.
    """
    if spec.tube.via_corners != BLEND_CORNERS or len(plan.times) < 3:
        return plan
    profile = profile or spec.tube.via_profile
    n = len(plan.lower[0])
    obstacles = np.array([[b.lower, b.upper] for b in spec.obstacle_boxes()]).reshape(-1, 2, n)
    space = (np.array(spec.state_space.lower), np.array(spec.state_space.upper))
    first, last = plan.times[0], plan.times[-1]
    plan = _roomier_corners(plan, obstacles, space, spec, profile)
    starts, ends = blended_times(plan, obstacles, space, profile)
    stretch = (ends[0] - starts[0]) / (plan.times[1] - plan.times[0])
    if stretch > 1.0:
        plan = _stopped_plan(plan.lower, plan.upper, (last - first) * stretch, spec, first,
                             profile)
        starts, ends = blended_times(plan, obstacles, space, profile)
    scale = (last - first) / (ends[-1] - first)

    def into(v: float) -> float:
        return first + (v - first) * scale

    return replace(plan, times=(first,) + tuple(into(v) for v in ends[:-1]) + (last,),
                   starts=tuple(into(v) for v in starts))


def _stopped_plan(lower: tuple, upper: tuple, duration: float, spec: Spec,
                  start: float = 0.0, profile: str | None = None) -> ViaPlan:
    """The via boxes ``lower``, ``upper`` timed by :func:`timed_moves` over ``[start, start +
    duration]``, every corner stopped."""
    centres = [0.5 * (np.array(lo) + np.array(hi)) for lo, hi in zip(lower, upper)]
    profile = profile or spec.tube.via_profile
    durations, profiles = timed_moves(spec, [b - a for a, b in zip(centres, centres[1:])],
                                      duration, profile)
    times = [start]
    for seconds in durations:
        times.append(times[-1] + seconds)
    times[-1] = start + duration
    # a zero-length move (same centre, other size) still needs a positive duration
    for k in range(1, len(times)):
        if times[k] <= times[k - 1]:
            times[k] = math.nextafter(times[k - 1], math.inf)
    chosen = tuple(profiles) if any(p != profile for p in profiles) else ()
    return ViaPlan(tuple(lower), tuple(upper), tuple(times), chosen)


#: Shifts of a via box away from the inside of its corner that :func:`_roomier_corners`
#: tries, as shares of the shorter of the corner's two moves, least first.
CORNER_SHIFTS = (0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4)


def _roomier_corners(plan: ViaPlan, obstacles: np.ndarray, space, spec: Spec,
                     profile: str) -> ViaPlan:
    """``plan`` with each via box whose corner cannot be blended by the largest share moved
    away from the inside of its turn (along ``u_in - u_out``, the difference of the unit
    directions of its two moves), by the least of :data:`CORNER_SHIFTS` at which both
    moves stay free (:func:`_free` of their bounding boxes) and the blend by the largest
    share of :data:`BLEND_SHARES` is free; re-timed after every move of a box. A box no
    shift frees stays where it is (and :func:`blended_times` takes a smaller share or
    stops there)."""
    def widest_free(trial: ViaPlan, j: int) -> bool:
        # corner j blended by the largest share on trial's timing
        durations = np.diff(np.array(trial.times, dtype=float))
        profiles = trial.profiles or (profile,) * len(durations)
        widest = BLEND_SHARES[0] * min(durations[j - 1], durations[j])
        return _overlap_free(trial, j - 1, durations, profiles, widest, obstacles, space)

    lower, upper = [np.array(b) for b in plan.lower], [np.array(b) for b in plan.upper]
    for j in range(1, len(lower) - 1):
        if widest_free(plan, j):
            continue
        centre = [0.5 * (lo + hi) for lo, hi in zip(lower, upper)]
        into, out = centre[j] - centre[j - 1], centre[j + 1] - centre[j]
        if min(np.linalg.norm(into), np.linalg.norm(out)) == 0.0:
            continue
        away = into / np.linalg.norm(into) - out / np.linalg.norm(out)
        if np.linalg.norm(away) < 1e-9:
            continue
        away = away / np.linalg.norm(away)
        reach = min(np.linalg.norm(into), np.linalg.norm(out))
        for shift in CORNER_SHIFTS:
            lo, hi = lower[j] + shift * reach * away, upper[j] + shift * reach * away
            swept_lo = np.array([np.minimum(lower[j - 1], lo), np.minimum(lo, lower[j + 1])])
            swept_hi = np.array([np.maximum(upper[j - 1], hi), np.maximum(hi, upper[j + 1])])
            if not _free(swept_lo, swept_hi, obstacles, space).all():
                continue
            trial_lower = [*lower[:j], lo, *lower[j + 1:]]
            trial_upper = [*upper[:j], hi, *upper[j + 1:]]
            trial = _stopped_plan(tuple(tuple(float(v) for v in b) for b in trial_lower),
                                  tuple(tuple(float(v) for v in b) for b in trial_upper),
                                  plan.times[-1] - plan.times[0], spec, plan.times[0],
                                  profile)
            if widest_free(trial, j):
                lower, upper, plan = trial_lower, trial_upper, trial
                break
    return plan


def blended_times(plan: ViaPlan, obstacles: np.ndarray, space,
                  profile: str = SMOOTHSTEP) -> tuple[tuple, tuple]:
    """Start and end of every move of ``plan`` with its corners blended, within its time.

    Each move keeps its share of the time; the next one starts before it ends, by the
    largest of :data:`BLEND_SHARES` (of the shorter of the two moves) over which the
    box's sweep, widened by :data:`VIA_MARGIN`, lies in the state space and misses every
    obstacle (:func:`_overlap_free`); by nothing where none does (the tube stops there).
    The sweep depends on the shares only, not on the time scale, so the overlaps are
    chosen first and then every duration is stretched by one factor until the last move
    ends where the plan's did.

    Parameters
    ----------
    plan : ViaPlan
        Stopped corners (``plan.starts`` empty), ``m >= 2`` moves.
    obstacles : ndarray, shape (B, 2, n)
        Lower and upper corners of the obstacle boxes.
    space : (ndarray, ndarray)
        The state space's lower and upper corners.
    profile : str
        The moves' profile where the plan has not chosen each one's.

    Returns
    -------
    starts, ends : tuple of float
        ``m`` entries each, seconds; ``ends[-1]`` is the plan's last time.
    """
    times, m = plan.times, len(plan.times) - 1
    durations = np.diff(np.array(times, dtype=float))
    profiles = plan.profiles or (profile,) * m
    overlap = np.zeros(m - 1)
    for k in range(m - 1):
        for fraction in BLEND_SHARES:
            share = fraction * min(durations[k], durations[k + 1])
            if share > 0.0 and _overlap_free(plan, k, durations, profiles, share, obstacles,
                                             space):
                overlap[k] = share
                break
    stretch = float(durations.sum()) / float(durations.sum() - overlap.sum())
    starts, ends, clock = [], [], times[0]
    for k in range(m):
        starts.append(clock)
        ends.append(clock + durations[k] * stretch)
        clock = ends[-1] - (overlap[k] * stretch if k < m - 1 else 0.0)
    ends[-1] = times[-1]
    for k in range(1, m):      # rounding: the order TubeDesign asks for kept
        starts[k] = max(starts[k], math.nextafter(starts[k - 1], math.inf),
                        ends[k - 2] if k >= 2 else times[0])
    return tuple(float(v) for v in starts), tuple(float(v) for v in ends)


#: Samples of an overlap in :func:`_overlap_free`.
OVERLAP_SAMPLES = 128


def _overlap_free(plan: ViaPlan, k: int, durations: np.ndarray, profiles, share: float,
                  obstacles: np.ndarray, space) -> bool:
    """Whether the box's sweep while moves ``k`` and ``k + 1`` overlap by ``share`` seconds
    keeps :data:`VIA_MARGIN` from every obstacle and stays in the state space.

    On a clock where move ``k`` lasts ``[0, T_k]`` and move ``k + 1`` starts at ``T_k -
    share``, the box is ``B_k + (B_{k+1} - B_k) p_k + (B_{k+2} - B_{k+1}) p_{k+1}``. On
    each of :data:`OVERLAP_SAMPLES` pieces of the overlap every progress is monotone, so
    each bound lies between its value at the piece's start and that value plus the sum
    of each move's share of the piece (with its sign): a box that holds the sweep.
    """
    from ..tube import reference
    lower, upper = np.array(plan.lower[k:k + 3]), np.array(plan.upper[k:k + 3])
    first = ReachSegment(0.0, float(durations[k]), plan.lower[k], plan.upper[k],
                         plan.lower[k + 1], plan.upper[k + 1], profiles[k])
    begin = float(durations[k]) - share
    second = ReachSegment(begin, begin + float(durations[k + 1]), plan.lower[k + 1],
                          plan.upper[k + 1], plan.lower[k + 2], plan.upper[k + 2],
                          profiles[k + 1])
    t = np.linspace(begin, float(durations[k]), OVERLAP_SAMPLES + 1)
    p1 = reference.segment_progress(first, t)[0][:, None]
    p2 = reference.segment_progress(second, t)[0][:, None]
    bounds = []
    for box in (lower, upper):
        move1, move2 = box[1] - box[0], box[2] - box[1]
        at = box[0] + move1 * p1 + move2 * p2
        d1, d2 = move1 * np.diff(p1, axis=0), move2 * np.diff(p2, axis=0)
        bounds.append((at[:-1] + np.minimum(d1, 0.0) + np.minimum(d2, 0.0),
                       at[:-1] + np.maximum(d1, 0.0) + np.maximum(d2, 0.0)))
    (low, _), (_, high) = bounds
    return bool(_free(low, high, obstacles, space).all())


def via_design(spec: Spec, base: TubeDesign) -> TubeDesign:
    """``base`` with its reach tube replaced by the via-point segments of :func:`plan_via`.

    Parameters
    ----------
    spec : Spec
        The spec.
    base : TubeDesign
        The design without circumvents (:func:`~.search.base_design`).

    Returns
    -------
    TubeDesign
        ``base`` through the via points, without circumvents, its segments of the profile
        ``spec.tube.via_profile``.

    Raises
    ------
    DesignError
        :func:`plan_via` finds no path.
    """
    return replace(base, segments=plan_via(spec, base).segments(spec.tube.via_profile),
                   circumvents=())
