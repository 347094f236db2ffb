"""Designing a tube that avoids moving obstacles where and when they are.

A spec's moving obstacles (``Spec.moving_obstacles``, :mod:`stt_codegen.spec.motion`) are
not seen by the static design search. :func:`design_moving` tries, in order, and returns the
first tube whose check (:func:`~stt_codegen.design.search.check_tube`, which certifies
space-time disjointness from every moving obstacle, :mod:`.certificate.motion`) passes:

1. **space-time** (``"space-time"``): the design for the static obstacles alone (the spec's
   own ``tube.method``), checked against the moving obstacles as they really are;
2. **re-timed via plan** (``"timed via"``): the via boxes of the static via-point design
   (first for the static obstacles alone, then going around the swept regions of one, two,
   ... of the moving obstacles, :func:`routes`), re-timed against the others on a grid
   of :data:`TIME_STEPS` steps over ``[0, t_c]``: a search over (via box, time step)
   that may wait at a via box or take a segment at one of
   :data:`DURATION_FACTORS` times its planned duration, each move kept clear (by
   :data:`~.via.VIA_MARGIN`) of the hull of every moving obstacle over the move's time,
   earliest arrival first (with ``[actuator]``: the least speed-up first, then the
   earliest arrival; deterministic: fixed orders, no randomness); with ``[[tasks]]``
   each task's hold segment (:func:`task_holds`) may instead start at any step and last
   any number of steps that keep it in its task's window (:data:`TASK_HOLD_SHARE`), with
   free waits before and after it;
3. **swept** (``"swept"``, conservative): each moving obstacle replaced by the static box
   holding every position it takes while active (clipped to the state space), and the
   static design run on that; refused when such a box meets the start or the target;
4. **detour** (``"timed via"`` too): for each moving obstacle the step-1 tube is not
   certified to miss, the via plan (tasks' plan included) around the box it sweeps over
   :data:`DETOUR_SPANS` seconds either side of where that tube comes closest to it
   (:func:`partial_spec`), re-timed as in step 2 against every moving obstacle as it moves.

With ``[actuator]`` the re-timed tubes of steps 2 and 4 (whose legs are faster or slower
than the static design's, with waits between them) are accepted only when the variant's
input proof (role ``input_proof``: law (13)'s, the cascade's, the base's) keeps the bound
along them, and carry that proof; the re-timing then drives a smooth-step plan's legs as
``"cruise"`` segments, tries the timings that drive no leg faster than planned first and
leaves out the fast durations until the proof holds (:func:`speed_limits`). Specs with
``tube.method = "paper"`` skip steps 2 and 4 (their tubes are via-point tubes). The argument and the limits: docs/moving-obstacles.md.
"""

from __future__ import annotations

import heapq
import math
import time
from collections.abc import Callable, Sequence
from itertools import combinations, islice
from dataclasses import replace

import numpy as np

from ..errors import DesignError
from ..spec.loader import Obstacle, Spec
from ..spec.motion import MovingObstacle
from ..spec.variants import variant_of
from ..spec.tasks import STAY, Task
from ..tube import reference
from ..tube.parameters import CRUISE, SMOOTHSTEP, ReachSegment, TubeDesign
from .failures import FailureKind
from .gain import with_gain
from .certificate.motion import MOVING_PROPERTY
from .result import METHOD_PAPER, METHOD_VIA, Design, TubeCheck
from .tasks import FREE_HOLD, STAY_LEAD, TaskPlan
from .swept import swept_spec
from .via import VIA_MARGIN

#: How the tube of a spec with moving obstacles was found (``Design.motion``).
MOTION_SPACE_TIME = "space-time"
MOTION_TIMED_VIA = "timed via"
MOTION_SWEPT = "swept"
#: Time steps of the re-timing grid over ``[0, t_c]``.
TIME_STEPS = 60
#: Durations a re-timed segment may take, as multiples of its planned duration.
DURATION_FACTORS = (1.0, 0.75, 1.5, 0.5, 2.0)
#: Sub-intervals on which a move is checked against the obstacles' hulls.
MOVE_CHECKS = 8
#: With ``[actuator]``: the windows of moves either side of a re-timed move over which its
#: speed is levelled with theirs (:func:`_levelled_moves`), in the order tried.
LEVEL_WINDOWS = (64, 16, 8, 4, 2, 1, 0)
#: Most sets of moving obstacles to go around that the re-timing step tries (:func:`routes`).
MAX_ROUTES = 16
#: Half-lengths (s) of the time spans around where the static tube meets a moving obstacle
#: over which the detour step (:func:`partial_spec`) sweeps it, in the order tried.
DETOUR_SPANS = (1.0, 2.0)
#: With ``[[tasks]]``: a reach task's waypoint box is held (``rho`` equal to it) over at
#: least this share of the task's window (at most ``FREE_HOLD`` seconds), inside the window.
TASK_HOLD_SHARE = 0.25


def static_part(spec: Spec) -> Spec:
    """``spec`` without the moving obstacles that only the space-time steps handle (what the
    static design search sees).

    An obstacle until a task (``MovingObstacle.until``) is kept: the tasks' plan keeps
    clear of the box it sweeps until that task's hold (:func:`~.tasks.plan_tasks`), and the
    certificate checks it until the tube is certified to meet the task
    (:func:`~.certificate.motion.until_ended`).

    Parameters
    ----------
    spec : Spec
        A spec, with or without moving obstacles.

    Returns
    -------
    Spec
        The same spec with only its obstacles until a task as ``moving_obstacles``.
    """
    return replace(spec, moving_obstacles=tuple(ob for ob in spec.moving_obstacles
                                                if ob.until is not None))


def moves(spec: Spec) -> bool:
    """Whether ``spec`` has moving obstacles that need :func:`design_moving` (obstacles
    until a task alone do not: the static design keeps clear of them, see
    :func:`static_part`).

    Parameters
    ----------
    spec : Spec

    Returns
    -------
    bool
    """
    return any(ob.until is None for ob in spec.moving_obstacles)


def partial_spec(spec: Spec, position: int, t_a: float, t_b: float) -> Spec | None:
    """``spec``'s static part plus the box moving obstacle ``position`` sweeps over
    ``[t_a, t_b]`` (met with its active interval, clipped to the state space) as a static
    obstacle: a spec to *plan* a detour on (the re-timing and the check still see the
    obstacle moving). ``None`` when that box meets the initial or the target set, or the
    interval misses the active one.

    Parameters
    ----------
    spec : Spec
        The spec.
    position : int
        Index of the moving obstacle in ``spec.moving_obstacles``.
    t_a, t_b : float
        The time interval swept, s, ``t_a < t_b`` for a non-empty sweep.

    Returns
    -------
    Spec or None
        The static spec with the swept box added, or None.
    """
    ob = spec.moving_obstacles[position]
    a, b = max(t_a, ob.active[0]), min(t_b, ob.active[1])
    if not a < b:
        return None
    lo, hi, _ = ob.hull([a], [b])
    space = spec.state_space
    lower = tuple(max(float(v), space.lower[d]) for v, d in zip(lo[0], ob.dims))
    upper = tuple(min(float(v), space.upper[d]) for v, d in zip(hi[0], ob.dims))
    if any(x >= y for x, y in zip(lower, upper)):
        return None
    swept = Obstacle(lower, upper, ob.dims, ob.source)
    box = swept.box(space)
    if box.meets(spec.initial_set) or box.meets(spec.target_set):
        return None
    return replace(spec, obstacles=spec.obstacles + (swept,), moving_obstacles=())


def routes(count: int) -> list[tuple[int, ...]]:
    """The sets of moving obstacles to go around (swept) while timing the others, in the
    order tried: none first, then by size, then by index; the set of all is not among
    them (that is the swept step); at most :data:`MAX_ROUTES`.

    Parameters
    ----------
    count : int
        Number of moving obstacles.

    Returns
    -------
    list of tuple of int
        Each a set of indices into ``spec.moving_obstacles``, increasing.
    """
    every = (c for size in range(count) for c in combinations(range(count), size))
    return list(islice(every, MAX_ROUTES))       # lazily: 2^count sets for many obstacles


def _clear(lower: np.ndarray, upper: np.ndarray, spec: Spec, t_a: np.ndarray,
           t_b: np.ndarray) -> np.ndarray:
    """Boolean (K,): box ``[lower[k], upper[k]]`` (shape (K, n)) keeps :data:`VIA_MARGIN`
    from every moving obstacle's hull over ``[t_a[k], t_b[k]]``."""
    ok = np.ones(len(t_a), dtype=bool)
    still, moving = _still_boxes(spec.moving_obstacles)
    for d, lo, hi, on, off in still:       # boxes that do not move, all at once
        present = (np.maximum(t_a[:, None], on) <= np.minimum(t_b[:, None], off))
        gap = np.maximum(lo - upper[:, None, d], lower[:, None, d] - hi).max(axis=2)
        ok &= np.all(~present | (gap > VIA_MARGIN), axis=1)
    for ob in moving:
        lo, hi, present = ob.hull(t_a, t_b)
        d = list(ob.dims)
        gap = np.maximum(lo - upper[:, d], lower[:, d] - hi).max(axis=1)
        ok &= ~present | (gap > VIA_MARGIN)
    return ok


#: The last obstacles :func:`_still_boxes` grouped, and the groups.
_STILL_CACHE: list = [None, None]


def _still_boxes(obstacles: tuple[MovingObstacle, ...]) -> tuple[list, list]:
    """The obstacles that do not move (one knot) as arrays per ``dims`` (``dims``, lower,
    upper (M, len(dims)), ``t_on``, ``t_off`` (M,)), and the others; the last answer is
    kept (the re-timing asks for the same obstacles many times)."""
    if _STILL_CACHE[0] is obstacles:
        return _STILL_CACHE[1]
    groups: dict[tuple[int, ...], list[MovingObstacle]] = {}
    moving = []
    for ob in obstacles:
        if len(ob.times) == 1:
            groups.setdefault(ob.dims, []).append(ob)
        else:
            moving.append(ob)
    still = []
    for dims, obs in groups.items():
        centre = np.array([ob.centres[0] for ob in obs])
        half = np.array([ob.half_size for ob in obs])
        still.append((list(dims), centre - half, centre + half,
                      np.array([ob.active[0] for ob in obs]),
                      np.array([ob.active[1] for ob in obs])))
    _STILL_CACHE[:] = [obstacles, (still, moving)]
    return still, moving


def _moves_clear(segs: Sequence[ReachSegment], spec: Spec) -> list[bool]:
    """Per segment of ``segs``: its reach box (monotone profile) misses every moving
    obstacle on ``[start, end]``, checked on :data:`MOVE_CHECKS` sub-intervals (the
    segments' boxes judged in one :func:`_clear`, row by row as one at a time)."""
    if not segs:
        return []
    # np.linspace(start, end, MOVE_CHECKS + 1) of every segment, in its own operations
    start = np.array([seg.start for seg in segs])
    end = np.array([seg.end for seg in segs])
    cuts = np.arange(MOVE_CHECKS + 1.0) * ((end - start) / MOVE_CHECKS)[:, None] + start[:, None]
    cuts[:, -1] = end
    with reference.numpy_math():
        p = reference.segments_progress(segs, cuts)
    a_lo, a_hi, b_lo, b_hi = (np.array([getattr(seg, name) for seg in segs])[:, None, :]
                              for name in ("lower_from", "upper_from", "lower_to", "upper_to"))
    p0, p1 = p[:, :-1, None], p[:, 1:, None]
    lo = np.minimum(a_lo + (b_lo - a_lo) * p0, a_lo + (b_lo - a_lo) * p1)
    hi = np.maximum(a_hi + (b_hi - a_hi) * p0, a_hi + (b_hi - a_hi) * p1)
    n = lo.shape[2]
    ok = _clear(lo.reshape(-1, n), hi.reshape(-1, n), spec, cuts[:, :-1].ravel(),
                cuts[:, 1:].ravel()).reshape(len(segs), MOVE_CHECKS)
    return ok.all(axis=1).tolist()


def task_holds(segments: Sequence[ReachSegment], spec: Spec,
               order: Sequence[int] | None = None) -> dict[int, Task] | None:
    """The hold segments of a tasks' plan (:func:`~.tasks.plan_tasks`), by segment index.

    Parameters
    ----------
    segments : sequence of ReachSegment
        A via plan of ``spec``.
    spec : Spec
        Its ``tasks``.
    order : sequence of int, optional
        The plan's visit order (``TaskPlan.order``); default the spec's order.

    Returns
    -------
    dict of int to Task, or None
        For each task, the index of the first segment after the previous task's that holds
        one box (``rho`` constant) over a sub-interval of ``[t0 - STAY_LEAD, t1]``; empty
        without tasks; ``None`` when some task has no such segment (not a tasks' plan).
    """
    out: dict[int, Task] = {}
    k = 0
    for task in (spec.tasks if order is None else [spec.tasks[j] for j in order]):
        t0, t1 = task.window
        while k < len(segments) and not (
                segments[k].lower_from == segments[k].lower_to
                and segments[k].upper_from == segments[k].upper_to
                and segments[k].start >= t0 - STAY_LEAD - 1e-9
                and segments[k].end <= t1 + 1e-9):
            k += 1
        if k == len(segments):
            return None
        out[k] = task
        k += 1
    return out


def _hold_ok(task: Task, start: float, end: float) -> bool:
    """Whether holding the waypoint box over ``[start, end]`` (s) serves ``task``: a stay
    task's whole window (its duration and ``STAY_LEAD`` inside the window, for a stay with
    a duration), or :data:`TASK_HOLD_SHARE` of a reach task's window inside it (at most
    ``FREE_HOLD`` seconds)."""
    t0, t1 = task.window
    if task.kind == STAY and task.duration is not None:
        return min(end, t1) - max(start, t0) >= task.duration + STAY_LEAD - 1e-9
    if task.kind == STAY:
        return start <= t0 + 1e-9 and end >= t1 - 1e-9
    return min(end, t1) - max(start, t0) >= min(TASK_HOLD_SHARE * (t1 - t0), FREE_HOLD) - 1e-9


def retime(segments: tuple[ReachSegment, ...], spec: Spec,
           order: Sequence[int] | None = None,
           factors: Sequence[float] = DURATION_FACTORS,
           memo: dict | None = None, level: bool = True,
           steps: int = TIME_STEPS) -> tuple[ReachSegment, ...] | None:
    """The via boxes of ``segments`` re-timed to miss the moving obstacles (module notes).

    The search settles (via box, step) states by their speed-up, then their step: without
    ``[actuator]`` every speed-up is 0 and the timing is the earliest arrival. With it, a
    segment driven in ``d`` steps of ``tau`` costs ``max(0, planned / (d tau) - 1)`` (how
    much faster than planned) and the timing is the one of least summed speed-up, then the
    earliest arrival among those: a leg is driven faster only where waiting needs it, as
    the input proof asks least of slow legs. An arrival in the target box counts only where
    the box stays clear from it until ``t_c`` (the tube waits there). With ``[actuator]``
    and no tasks, the timing found is then levelled (:func:`_levelled_moves`): its waits spent
    driving slower where the moves keep clear.

    With ``spec.tasks``, each task's hold segment (:func:`task_holds`) is not re-timed by
    :data:`DURATION_FACTORS`: it may start at any step and last any number of steps such
    that the held interval serves its task (:func:`_hold_ok`) and the box keeps clear over
    it; the waits before and after it are free.

    Parameters
    ----------
    segments : tuple of ReachSegment
        The static plan's segments (via boxes), in order.
    spec : Spec
        The spec with its moving obstacles (and tasks).
    order : sequence of int, optional
        The tasks' visit order (``TaskPlan.order``); default the spec's order.
    factors : sequence of float, optional
        The durations a segment may take, as multiples of its planned duration, in the
        order tried (default :data:`DURATION_FACTORS`; with ``[actuator]`` the design
        leaves out the fast ones the base cannot drive, :func:`speed_limits`).
    memo : dict, optional
        The moves judged so far, by (box, step, steps): a memo shared by the calls with the
        same ``segments`` and ``spec`` (other ``factors``), which judge many of the same
        moves; filled here.
    level : bool
        With ``[actuator]`` (and no tasks), the timing found levelled (:func:`_levelled_moves`);
        ``False``: the search's own.
    steps : int
        The grid's steps over ``[0, t_c]`` (default :data:`TIME_STEPS`; a fleet's
        re-timings use a finer one, :data:`~.fleet.FLEET_TIME_STEPS`).

    Returns
    -------
    tuple of ReachSegment or None
        Segments through the same boxes, with waits between them (the reach tube holds a
        box between two segments), the last ending by ``t_c``; ``None`` if the search
        finds no timing (or ``segments`` is not a plan of ``spec``'s tasks).
    """
    t_c = spec.prescribed_time
    tau = t_c / steps
    m = len(segments)
    holds = task_holds(segments, spec, order)
    if holds is None:
        return None
    boxes = [(np.array(s.lower_from), np.array(s.upper_from)) for s in segments]
    boxes.append((np.array(segments[-1].lower_to), np.array(segments[-1].upper_to)))
    grid = np.arange(steps + 1)
    # waits: box k over [i tau, (i + 1) tau], for every i at once
    waits = [_clear(np.tile(lo, (steps + 1, 1)), np.tile(hi, (steps + 1, 1)), spec,
                    grid * tau, (grid + 1) * tau) for lo, hi in boxes]
    # the tube waits in the target box from its arrival to t_c: an arrival at step i is a
    # goal only where that wait is clear
    lo, hi = boxes[m]
    parked = _clear(np.tile(lo, (steps + 1, 1)), np.tile(hi, (steps + 1, 1)), spec,
                    grid * tau, np.full(steps + 1, t_c))
    # parent[(k, i)] = (previous state, segment taken or None for a wait); states are
    # settled by (summed speed-up, step, box): without [actuator] every speed-up is 0 and
    # the first parent found is kept, a breadth-first search in time (earliest arrival)
    speed_up = spec.input_bound is not None
    memo = {} if memo is None else memo
    parent: dict[tuple[int, int], tuple[tuple[int, int] | None, ReachSegment | None]] = {
        (0, 0): (None, None)}
    cost = {(0, 0): 0.0}
    heap = [(0.0, 0, 0)]
    goal = None

    def reach(to: tuple[int, int], came: tuple[int, int], seg: ReachSegment | None,
              extra: float = 0.0) -> None:
        c = cost[came] + extra
        if to in cost and cost[to] <= c:
            return
        cost[to], parent[to] = c, (came, seg)
        heapq.heappush(heap, (c, to[1], to[0]))

    while heap:
        c, i, k = heapq.heappop(heap)
        if c > cost[(k, i)]:           # a stale entry: the state was reached cheaper since
            continue
        if k == m:
            if parked[i]:
                goal = (k, i)
                break
            continue
        if i < steps and waits[k][i]:
            reach((k, i + 1), (k, i), None)
        if k in holds:
            # hold the waypoint box from step i to step j (clear: the waits' boxes)
            for j in range(i + 1, steps + 1):
                if not waits[k][j - 1]:
                    break
                if _hold_ok(holds[k], i * tau, j * tau):
                    reach((k + 1, j), (k, i), replace(segments[k], start=i * tau, end=j * tau))
            continue
        planned = segments[k].end - segments[k].start
        moves = []                      # (factor's steps, target state, segment)
        for f in factors:
            d = max(1, int(math.ceil(f * planned / tau - 1e-9)))
            to = (k + 1, i + d)
            if to[1] > steps or (to in cost and cost[to] <= c):
                continue
            seg = replace(segments[k], start=i * tau, end=(i + d) * tau)
            if to[0] == m:
                seg = replace(seg, end=min(seg.end, t_c))
            moves.append((d, to, seg))
        # every move's clearance at once (reach only lowers costs: a move skipped above is
        # skipped below too, and one judged here and skipped below costs only its check)
        fresh = [((k, i, d), seg) for d, _, seg in moves if (k, i, d) not in memo]
        if fresh:
            memo.update(zip([key for key, _ in fresh], _moves_clear([seg for _, seg in fresh],
                                                                    spec)))
        for d, to, seg in moves:
            if to in cost and cost[to] <= c:
                continue
            if memo[(k, i, d)]:
                reach(to, (k, i), seg, max(0.0, planned / (d * tau) - 1.0) if speed_up else 0.0)
    if goal is None:
        return None
    out = []
    state: tuple[int, int] | None = goal
    while state is not None:
        state, seg = parent[state]
        if seg is not None:
            out.append(seg)
    out.reverse()
    return _held(_levelled_moves(out, spec) if speed_up and level and not holds else tuple(out))


def levelled_timing(segments: Sequence[ReachSegment], spec: Spec) -> tuple[ReachSegment, ...]:
    """A timing's segments (contiguous, a wait a segment whose box does not change) with
    their moves' speeds levelled against ``spec``'s moving obstacles (:func:`_levelled_moves`).

    Parameters
    ----------
    segments : sequence of ReachSegment
        Contiguous in time from ``t = 0``, ending by ``spec.prescribed_time``.
    spec : Spec
        Its ``moving_obstacles`` are what every levelled move keeps clear of.

    Returns
    -------
    tuple of ReachSegment
        The same moves through the same boxes, in the same order, contiguous.
    """
    moves = [seg for seg in segments
             if seg.lower_from != seg.lower_to or seg.upper_from != seg.upper_to]
    return _held(_levelled_moves(moves, spec))


def _levelled_moves(moves: list[ReachSegment], spec: Spec) -> tuple[ReachSegment, ...]:
    """The moves of a timing with ``[actuator]``, their speeds levelled where they keep
    clear. A grid's timing drives a move in a whole number of steps and waits whole steps,
    so neighbouring legs alternate between a speed below their plan and one above it; the
    input proof asks least of the slowest legs. The fastest move first (a move's speed:
    the longer of its box's two corners' moves over its duration): over a window of moves
    around it (the widest of :data:`LEVEL_WINDOWS` moves either side first), the window's
    time, with the waits just outside it or without them (for a move alone, also with one
    of them or half of either: :func:`_spans`), is shared in proportion to the moves'
    lengths (one speed; a move whose box does not move keeps its duration); the first
    window whose moves are all judged clear as the search judges a move
    (:func:`_moves_clear`) and whose fastest is slower than that move is kept; a move that
    no window slows is left. A wait shortened is clear (a sub-interval of a clear one);
    every changed move is judged again, and the tube's certificate and input proof judge
    the whole."""
    moves = list(moves)
    m, t_c = len(moves), spec.prescribed_time
    lengths = np.array([max(float(np.linalg.norm(np.subtract(s.lower_to, s.lower_from))),
                            float(np.linalg.norm(np.subtract(s.upper_to, s.upper_from))))
                        for s in moves])

    def speed(j: int, seg: ReachSegment) -> float:
        return float(lengths[j] / max(seg.end - seg.start, 1e-12))

    def levelled(a: int, b: int, t0: float, t1: float) -> list[ReachSegment] | None:
        # a move that does not move keeps its duration; the others share the rest
        fixed = np.array([0.0 if lengths[j] > 0.0 else moves[j].end - moves[j].start
                          for j in range(a, b + 1)])
        share = t1 - t0 - fixed.sum()
        if share <= 0.0 or lengths[a:b + 1].sum() <= 0.0:
            return None
        cuts = np.empty(b - a + 2)
        cuts[0] = t0
        cuts[1:] = t0 + np.cumsum(fixed + share * lengths[a:b + 1] / lengths[a:b + 1].sum())
        cuts[-1] = t1
        return [replace(moves[a + j], start=float(cuts[j]), end=float(cuts[j + 1]))
                for j in range(b - a + 1)]

    left = set(range(m))
    for _ in range(2 * m):
        if not left:
            break
        k = max(left, key=lambda j: (speed(j, moves[j]), -j))
        fastest = speed(k, moves[k])
        for width in LEVEL_WINDOWS:
            a, b = max(0, k - width), min(m - 1, k + width)
            kept = None
            for t0, t1 in _spans(moves[a - 1].end if a else 0.0, moves[a].start, moves[b].end,
                                 moves[b + 1].start if b + 1 < m else t_c, a == b):
                tried = levelled(a, b, t0, t1)
                if tried is None:
                    continue
                slowed = max(speed(a + j, seg) for j, seg in enumerate(tried)) < (
                    fastest * (1.0 - 1e-6))
                if slowed and all(_moves_clear(tried, spec)):
                    kept = tried
                    break
            if kept is not None:
                moves[a:b + 1] = kept
                left |= set(range(a, b + 1))
                break
        else:
            left.discard(k)
    return tuple(moves)


def _spans(before: float, start: float, end: float, after: float,
           alone: bool) -> list[tuple[float, float]]:
    """The spans a window of moves from ``start`` to ``end`` may be levelled over, between
    the end of the move before it (``before``) and the start of the move after it
    (``after``): the whole of both waits, or none; for a single move (``alone``) also each
    wait or half of it on either side, longest first."""
    if not alone:
        return [(before, after), (start, end)]
    firsts = (before, (before + start) / 2, start)
    lasts = (after, (end + after) / 2, end)
    spans = {(t0, t1) for t0 in firsts for t1 in lasts} - {(start, end)}
    return sorted(spans, key=lambda span: (span[0] - span[1], span))


def _held(segments: tuple[ReachSegment, ...]) -> tuple[ReachSegment, ...]:
    """``segments`` with a wait between two of them as a segment that holds the box (the
    reach tube's segments are contiguous in time)."""
    out: list[ReachSegment] = []
    for seg in segments:
        if out and seg.start > out[-1].end:
            last = out[-1]
            out.append(replace(last, start=last.end, end=seg.start,
                               lower_from=last.lower_to, upper_from=last.upper_to))
        out.append(seg)
    return tuple(out)


def design_moving(spec: Spec, design_static: Callable[[Spec], Design],
                  check: Callable[[TubeDesign, Spec], TubeCheck]) -> Design:
    """Design a certified tube for a spec with moving obstacles (see the module notes).

    Parameters
    ----------
    spec : Spec
        With ``moving_obstacles``.
    design_static : callable
        :func:`~stt_codegen.design.search.design_tube` (passed in: this module is below it).
    check : callable
        :func:`~stt_codegen.design.search.check_tube`.

    Returns
    -------
    Design
        For ``spec`` (its check includes ``avoids moving obstacle j`` for each), with
        ``motion`` saying which of the three ways found it.

    Raises
    ------
    DesignError
        No design avoids the static obstacles (the static search's error), or none of the
        three ways gives a tube that passes; the message says what each found, ``kind``
        is the space-time check's (``MOVING_OBSTACLE`` usually) or ``SWEPT_AT_START``,
        ``tried`` the static design's tube.
    """
    started = time.perf_counter()
    static = static_part(spec)
    first = design_static(static)        # a static failure is final: raise it as it is
    found = check(first.tube, spec)
    if found.passed:
        return _design(first.tube, first.method, found, spec, started, MOTION_SPACE_TIME,
                       first)
    reasons = [f"the {first.method} design for the static obstacles fails in space-time: "
               f"{found.reason}"]
    kind = found.kind
    if spec.tube.method != METHOD_PAPER:
        tried: list[str] = []
        for which in routes(len(spec.moving_obstacles)):
            partial, _ = swept_spec(spec, which)
            if partial is None:
                continue
            around = static_part(partial)
            via = (first if not which and first.method == METHOD_VIA else
                   _try(lambda: design_static(replace(around, tube=replace(around.tube,
                                                                           method="via")))))
            timed = retimed_design(via, partial, spec, check, started)
            if timed is None:
                continue
            if isinstance(timed, Design):
                return timed
            tried.append(f"the re-timed via tube around {list(which) or 'none'} fails: "
                         f"{timed}")
        reasons.append("; ".join(tried) if tried else
                       f"no re-timing of the via boxes on {TIME_STEPS} time steps keeps "
                       "clear of the moving obstacles (going around none, one or more of "
                       "them)")
    swept, why = swept_spec(spec)
    if swept is None:
        reasons.append(f"no swept design: {why}")
        kind = FailureKind.SWEPT_AT_START
    else:
        try:
            design = design_static(swept)
        except DesignError as exc:
            reasons.append(f"no design avoids the swept regions: {exc}")
        else:
            final = check(design.tube, spec)
            if final.passed:
                return _design(design.tube, design.method, final, spec, started,
                               MOTION_SWEPT, design)
            reasons.append(f"the swept design fails: {final.reason}")
    if spec.tube.method != METHOD_PAPER:
        detoured, why = _detour(spec, found, design_static, check, started)
        if detoured is not None:
            return detoured
        reasons.append(why)
    raise DesignError("no tube avoids the moving obstacles: " + "; ".join(reasons),
                      kind=kind, tried=first.tube)


def _detour(spec: Spec, found: TubeCheck, design_static: Callable[[Spec], Design],
            check: Callable[[TubeDesign, Spec], TubeCheck],
            started: float) -> tuple[Design | None, str]:
    """Step 4 (module notes): a via plan around the box a moving obstacle sweeps near where
    the static tube ``found`` meets it, re-timed against every moving obstacle; the design,
    or ``None`` and what was found."""
    tried: list[str] = []
    for position, when in _meetings(found, spec):
        for span in DETOUR_SPANS:
            planning = partial_spec(spec, position, when - span, when + span)
            via = None if planning is None else _try(lambda: design_static(
                replace(planning, tube=replace(planning.tube, method="via"))))
            timed = retimed_design(via, spec, spec, check, started)
            if timed is None:
                continue
            if isinstance(timed, Design):
                return timed, ""
            tried.append(f"the re-timed via tube around moving obstacle "
                         f"{spec.moving_obstacles[position].source} over "
                         f"[{when - span:g}, {when + span:g}] s fails: {timed}")
    return None, ("; ".join(tried) if tried else "no detour around where the static tube "
                  "meets a moving obstacle is planned and re-timed")


def retimed_design(via: Design | None, timing: Spec, spec: Spec,
                   check: Callable[[TubeDesign, Spec], TubeCheck],
                   started: float, steps: int = TIME_STEPS) -> Design | str | None:
    """``via``'s boxes re-timed against the moving obstacles of ``timing``
    (:func:`retime`) and checked for ``spec`` (with ``[actuator]``, its input proof too).

    Parameters
    ----------
    via : Design or None
        A via-point design (its segments' boxes and, with tasks, its plan's order).
    timing : Spec
        Its ``moving_obstacles`` are what the re-timing keeps clear of.
    spec : Spec
        The spec the re-timed tube is checked and designed for.
    check : callable
        ``check(tube, spec) -> TubeCheck`` (:func:`~.search.check_tube`, or a check that
        asks more of the tube, as the fleet design's).
    started : float
        ``time.perf_counter()`` when the design began (its ``design_time_s``).
    steps : int
        The re-timing grid's steps over ``[0, t_c]`` (:func:`retime`).

    Returns
    -------
    Design, str or None
        The design (``motion`` ``"timed via"``) when the check (and the input proof)
        pass; why not otherwise; ``None`` when ``via`` is ``None`` or no re-timing is
        found.
    """
    if via is None:
        return None
    why = None
    planned = via.tube.segments
    if spec.input_bound is not None:      # the lower peak rate for the same duration
        planned = tuple(replace(seg, profile=CRUISE) if seg.profile == SMOOTHSTEP else seg
                        for seg in planned)
    tried: set[tuple[ReachSegment, ...]] = set()
    none: list[set[float]] = []       # factor sets with no timing: none in a subset either
    judged: dict = {}                 # the moves' clearances, the same for every factor set
    for factors in speed_limits(spec):
        if any(set(factors) <= fewer for fewer in none):
            continue
        order = via.task_plan.order if via.task_plan is not None else None
        segments = retime(planned, timing, order, factors, judged, steps=steps)
        if segments is None:
            none.append(set(factors))
        if segments is None or segments in tried:     # the same timing: the same verdict
            continue
        tried.add(segments)
        tube = replace(via.tube, segments=segments)
        timed = check(tube, spec)
        if not timed.passed and spec.input_bound is not None:
            # levelled, its moves judged clear as the search judges them; the whole check
            # failed: the search's own timing (faster legs, whose proof may still hold)
            searched = retime(planned, timing, order, factors, judged, level=False,
                              steps=steps)
            if searched is not None and searched not in tried:
                tried.add(searched)
                tube = replace(via.tube, segments=searched)
                timed = check(tube, spec)
        if not timed.passed:
            why = timed.reason
            continue
        design = _design(with_gain(tube, timed.min_width, spec), METHOD_VIA, timed, spec, started,
                         MOTION_TIMED_VIA, via)
        if spec.input_bound is None:
            return design
        proof = variant_of(spec).entry("input_proof")(design, spec)
        if proof.meets(spec.input_bound):
            return replace(design, input_proof=proof)
        peaks = ", ".join(f"|{name}| <= {p:.4g}" for name, p in
                          zip(spec.input_names, proof.peak))
        if not proof.complete:              # stopped at the first sample over the bound
            peaks += f" up to t = {max(proof.time):.3f} s, where the proof stopped"
        why = (f"its input is not proved within actuator.input_bound ({peaks}, the "
               f"segments at {min(factors):g} times their planned durations or slower)"
               if proof.proved else f"its input bound is not proved: {proof.reason}")
    return why


def speed_limits(spec: Spec) -> list[tuple[float, ...]]:
    """The sets of :data:`DURATION_FACTORS` the re-timing tries, in order.

    Without ``[actuator]`` all of them at once. With it, a faster segment asks more of the
    actuators, so the re-timing is tried with the factors at least each of
    :data:`DURATION_FACTORS`: first those at least 1 in increasing order (no leg faster
    than planned; then slower), then those below 1 in decreasing order (at least 0.75,
    then all): the timing of least speed-up of each set (:func:`retime`), and the first
    whose input proof keeps the bound wins (a plan that waits, then drives its legs no
    faster than the base can). A set within one that has no timing is skipped (it has
    none either). With
    ``[actuator]`` the re-timed segments of a smooth-step plan are ``"cruise"`` segments
    (the same boxes and durations, a peak rate 1.25 times the mean instead of 1.875).

    Parameters
    ----------
    spec : Spec

    Returns
    -------
    list of tuple of float
        Each in the order of :data:`DURATION_FACTORS`.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> speed_limits(stt.load_spec("crossing-moving"))
    [(1.0, 0.75, 1.5, 0.5, 2.0)]
    """
    if spec.input_bound is None:
        return [DURATION_FACTORS]
    no_faster = sorted(f for f in set(DURATION_FACTORS) if f >= 1.0)
    faster = sorted((f for f in set(DURATION_FACTORS) if f < 1.0), reverse=True)
    return [tuple(f for f in DURATION_FACTORS if f >= slowest)
            for slowest in no_faster + faster]


def _meetings(found: TubeCheck, spec: Spec) -> list[tuple[int, float]]:
    """(position in ``spec.moving_obstacles``, time of the smallest margin, s) of each
    moving obstacle the checked tube is not certified to miss, in the spec's order."""
    margins = {m.name: m for m in found.certificate.margins}
    out = []
    for position, ob in enumerate(spec.moving_obstacles):
        m = margins.get(f"{MOVING_PROPERTY} {ob.source}")
        if m is not None and not m.passed:
            out.append((position, float(m.time)))
    return out


def _try(make: Callable[[], Design]) -> Design | None:
    try:
        return make()
    except DesignError:
        return None


def _design(tube: TubeDesign, method: str, check: TubeCheck, spec: Spec, started: float,
            motion: str, source: Design) -> Design:
    return Design(tube, method, check, time.perf_counter() - started, spec=spec,
                  input_proof=source.input_proof, motion=motion,
                  task_choices=source.task_choices,
                  task_plan=retimed_plan(tube.segments, spec, source.task_plan))


def retimed_plan(segments: Sequence[ReachSegment], spec: Spec,
                 plan: TaskPlan | None) -> TaskPlan | None:
    """The visits of a tasks' plan after :func:`retime`: the same order, each task's hold
    the interval over which ``segments`` keep ``rho`` at its waypoint box (from the end of
    the segment that reaches the box to the start of the one that leaves it, waits
    included).

    Parameters
    ----------
    segments : sequence of ReachSegment
        The re-timed plan (or any via plan of ``spec``'s tasks).
    spec : Spec
        Its ``tasks``.
    plan : TaskPlan or None
        The plan before re-timing (its ``order``).

    Returns
    -------
    TaskPlan or None
        ``None`` when ``plan`` is ``None`` or ``segments`` hold no box for some task.
    """
    if plan is None:
        return None
    holds = task_holds(segments, spec, plan.order)
    if holds is None:
        return None
    held = {}
    for task_index, k in zip(plan.order, holds):      # holds: segment indices in visit order
        start = segments[k - 1].end if k > 0 else 0.0
        end = segments[k + 1].start if k + 1 < len(segments) else spec.prescribed_time
        held[task_index] = (float(start), float(end))
    return TaskPlan(plan.order, tuple(held[j] for j in range(len(spec.tasks))))


__all__ = ["DETOUR_SPANS", "DURATION_FACTORS", "LEVEL_WINDOWS", "MAX_ROUTES", "MOTION_SPACE_TIME",
           "MOTION_SWEPT", "MOTION_TIMED_VIA", "MOVE_CHECKS", "TASK_HOLD_SHARE", "TIME_STEPS",
           "design_moving", "levelled_timing", "moves", "retime", "retimed_design",
           "retimed_plan", "routes", "partial_spec", "speed_limits", "static_part", "task_holds"]
