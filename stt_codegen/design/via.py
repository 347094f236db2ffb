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
from ..tube.parameters import (CRUISE, SCURVE, SMOOTHSTEP, ReachSegment, TubeDesign,
                               peak_acceleration_factor, peak_rate_factor)

__all__ = ["ACCELERATION_PROFILES", "ACCELERATION_TIMING", "LENGTH_TIMING", "VIA_HALF_WIDTH",
           "VIA_MARGIN", "VIA_TIMINGS", "ViaPlan", "move_weight", "plan_via",
           "timed_moves", "via_design"]

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
VIA_TIMINGS = (LENGTH_TIMING, ACCELERATION_TIMING)
#: The profiles a move timed for the acceleration may take, least peak acceleration first
#: (peak rates 2, 15/8 and 1.25 times the mean): from the spec's ``tube.via_profile`` on.
ACCELERATION_PROFILES = (SCURVE, SMOOTHSTEP, CRUISE)


def move_weight(length: float, timing: str) -> float:
    """A move's share of time before normalisation: its duration is this over the sum of
    its plan's (or leg's) weights times the time the plan has.

    Parameters
    ----------
    length : float
        The move's centre distance (max norm), state units.
    timing : {"length", "acceleration"}
        :data:`LENGTH_TIMING` (``length``) or :data:`ACCELERATION_TIMING`
        (``sqrt(length)``).

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
    raise ValueError(f"unknown via timing {timing!r}: one of {', '.join(VIA_TIMINGS)}")


def timed_moves(spec: Spec, moves: list[np.ndarray], duration: float, profile: str
                ) -> tuple[list[float], list[str]]:
    """The moves' durations sharing ``duration``, and each move's profile.

    With the length timing, or without ``state_space.velocity_bound``, each move's share is
    its :func:`move_weight` over their sum and every move has ``profile``. Timed for the
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
    lengths = [float(np.max(np.abs(m))) for m in moves]
    weights = [move_weight(length, timing) for length in lengths]
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
        ``t_0 = 0 < t_1 < ... < t_m <= t_c``, seconds: the tube is in ``B_k`` at ``t_k``.
    profiles : tuple of str
        Each move's profile where :func:`timed_moves` chose it (``m`` entries), else empty.
    """

    lower: tuple[tuple[float, ...], ...]
    upper: tuple[tuple[float, ...], ...]
    times: tuple[float, ...]
    profiles: tuple[str, ...] = ()

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
        return tuple(ReachSegment(self.times[k], self.times[k + 1], self.lower[k],
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
    centres = [0.5 * (nodes[k][0] + nodes[k][1]) for k in path]
    durations, profiles = timed_moves(spec, [b - a for a, b in zip(centres, centres[1:])],
                                      prescribed_time, spec.tube.via_profile)
    times = [0.0]
    for seconds in durations:
        times.append(times[-1] + seconds)
    times[-1] = prescribed_time
    # a zero-length move (same centre, other size) still needs a positive duration
    for k in range(1, len(times)):
        if times[k] <= times[k - 1]:
            times[k] = math.nextafter(times[k - 1], math.inf)
    lower = tuple(tuple(float(v) for v in nodes[k][0]) for k in path)
    upper = tuple(tuple(float(v) for v in nodes[k][1]) for k in path)
    chosen = tuple(profiles) if any(p != spec.tube.via_profile for p in profiles) else ()
    return ViaPlan(lower, upper, tuple(times), chosen)


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
