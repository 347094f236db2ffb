"""Timed tasks as via plans: the reach tube through each task's box inside its window.

A spec's ``[[tasks]]`` (:mod:`stt_codegen.spec.tasks`, docs/tasks.md) become *waypoints*
of the via-point design (:mod:`stt_codegen.design.via`), in window order, then the target:

* **Waypoint box.** Inside the task's box (the chosen ``any_of`` alternative), a box of
  half-width ``min(TASK_BOX_SHARE * h_i, max(d_0i, d_Ti))`` per dimension (``h`` the task
  box's half-width, ``d_0``, ``d_T`` the spec's initial and target half-widths), kept
  ``TASK_ROOM * h_i`` from the task box's walls, centred as near as it may be to the
  previous waypoint's centre (the shortest move in).
* **Hold.** The reach tube ``rho`` stays equal to the waypoint box over a hold interval:
  for a reach task the middle of its window, ``[t0 + HOLD_LEAD w, t1 - HOLD_LEAD w]``
  (``w = t1 - t0``); for a stay task the whole window, entered up to ``STAY_LEAD`` seconds
  early (at most a quarter of the time since the previous hold ended). A stay window that
  leaves no time to move (one from ``t = 0``) holds the box the tube is already in
  (``X-hat_0``, or the previous waypoint) when that box lies inside the stay box.
* **Legs.** Between two holds (and from ``X-hat_0`` at 0 to the first, and from the last
  to the target box ``T-hat`` at ``t_c``), :func:`~stt_codegen.design.via.plan_via` plans
  via boxes through the free space over the leg's duration: the same grid, moves,
  shortening and timing as a whole via design, with ``"cruise"`` segments (peak rate
  1.25 times the mean, :data:`~stt_codegen.tube.parameters.CRUISE`). Under free timing
  each leg's time follows its via path's length (largest coordinate moves), so every leg
  moves at about the same speed. With ``spec.tube.via_timing = "acceleration"`` (a
  second-order spec within ``[actuator]``: its input is a force) the legs are
  ``spec.tube.via_profile`` segments (the smooth step, peak acceleration ``5.77 D / T^2``
  against the cruise's ``9.4 D / T^2``, or the S-curve's ``4.76 D / T^2``) and every time
  follows the square roots of the moves' lengths
  (:func:`~stt_codegen.design.via.move_weight`), so every move asks about the same
  acceleration; a move whose profile would pass the velocity bound is slowed to it, as a
  cruise where that is cheaper (:func:`~stt_codegen.design.via.timed_moves`).

The certificate (:mod:`stt_codegen.design.certificate.tasks`) then proves each task for
every ``t``; the plan only makes it likely to pass. The plans (visit order and ``any_of``
alternatives) are tried shortest path first (:func:`task_plans`, at most
:data:`MAX_PLANS`); :func:`~stt_codegen.design.search.design_tube` keeps the first plan
whose tube passes its check.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from itertools import islice, permutations, product
from math import factorial

import numpy as np

from ..errors import DesignError
from ..spec.loader import Spec
from ..spec.tasks import STAY, Task
from ..tube.parameters import CRUISE, ReachSegment, TubeDesign, paper_segments
from .failures import FailureKind
from .swept import swept_spec
from .via import (BLEND_CORNERS, LENGTH_TIMING, ViaPlan, blend_plan, move_weight, plan_via,
                  timed_moves)

__all__ = ["FREE_HOLD", "MAX_PLANS", "STAY_LEAD", "TaskPlan", "plan_tasks", "task_plans",
           "task_schedule", "visit_orders"]

#: A waypoint box's half-width, at most this share of the task box's.
TASK_BOX_SHARE = 0.6
#: Room kept between a waypoint box and its task box's walls, share of the task box's
#: half-width (the tube is wider than ``rho`` by the adaptive ``alpha``).
TASK_ROOM = 0.2
#: A reach task's hold starts this share of its window after the window opens and ends
#: the same share before it closes.
HOLD_LEAD = 0.25
#: A stay task's hold starts up to this many seconds before its window opens.
STAY_LEAD = 0.25
#: Most plans (visit order and ``any_of`` alternatives) tried.
MAX_PLANS = 16
#: Free timing: a reach task's hold lasts this share of its window, at most
#: :data:`FREE_HOLD` seconds, and is kept half as much from the window's ends.
FREE_HOLD_SHARE = 0.25
FREE_HOLD = 0.5
#: Free timing: the shortest leg between two holds, seconds.
MIN_LEG = 0.25
#: Free timing: the estimated speeds tried, multiples of the even speed (the legs' path
#: length over the time the holds leave).
SPEED_FACTORS = (1.0, 2.0, 4.0)
#: ``[task_order] order = "any"``: every order is tried up to this many tasks; beyond,
#: nearest neighbour then 2-opt on the estimated travel.
EXACT_ORDERS = 6
#: ``order = "any"``: orders handed to the certificate at most (shortest first).
MAX_ORDERS = 4
#: Most (visit order, ``any_of`` combination) pairs ranked by their travel
#: (:func:`task_plans`).
MAX_COMBINATIONS = 2048


def waypoint_box(task: Task, choice: int, previous: np.ndarray,
                 base: TubeDesign) -> tuple[np.ndarray, np.ndarray]:
    """The waypoint box of a task (module notes): lower and upper corners, shape (n,)."""
    box = task.boxes[choice]
    lo, hi = np.array(box.lower), np.array(box.upper)
    h = 0.5 * (hi - lo)
    spec_half = np.maximum(0.5 * (np.array(base.initial_upper) - np.array(base.initial_lower)),
                           0.5 * (np.array(base.target_upper) - np.array(base.target_lower)))
    half = np.minimum(TASK_BOX_SHARE * h, spec_half)
    room = TASK_ROOM * h
    centre = np.clip(previous, lo + half + room, hi - half - room)
    return centre - half, centre + half


def _within(box: tuple, task_box) -> bool:
    """Whether ``box`` (lower, upper) lies inside ``task_box`` (the certificate then says
    whether the tube, wider by ``alpha``, does)."""
    return bool(np.all(np.array(box[0]) >= task_box.lower)
                and np.all(np.array(box[1]) <= task_box.upper))


def _around(spec: Spec, pending: list[int]) -> Spec:
    """The spec a leg is planned on: the obstacles until a task that is not yet met
    (positions ``pending`` in ``spec.moving_obstacles``) as the static boxes they sweep
    (:func:`~.swept.swept_spec`; ``spec`` itself when one meets the start or the target:
    the certificate then decides)."""
    if not pending:
        return spec
    around, _ = swept_spec(spec, pending)
    return spec if around is None else around


def _distance(a: np.ndarray, b: np.ndarray) -> float:
    """The largest coordinate move from ``a`` to ``b``, state units: the time a move
    takes at a given peak rate of every bound (law (13) bounds each input on its own)."""
    return float(np.max(np.abs(b - a)))


def _leg_path(spec: Spec, base: TubeDesign, start: tuple, goal: tuple) -> ViaPlan:
    """The via boxes from box ``start`` to box ``goal``, timed over ``[0, 1]`` (the path
    does not depend on the leg's duration; :func:`_leg` times it)."""
    return plan_via(spec, replace(base, prescribed_time=1.0,
                                  segments=paper_segments(*start, *goal, 1.0)))


def _path_length(plan: ViaPlan, timing: str = LENGTH_TIMING) -> float:
    """The via boxes' centres' path length (:func:`_distance` per move), state units; with
    another ``timing`` the sum of the moves' :func:`~.via.move_weight`."""
    return sum(move_weight(float(np.max(np.abs(m))), timing) for m in _moves(plan))


def _moves(plan: ViaPlan) -> list[np.ndarray]:
    """The via boxes' centres' displacements, state units, one per move."""
    centres = [_centre((lo, hi)) for lo, hi in zip(plan.lower, plan.upper)]
    return [b - a for a, b in zip(centres, centres[1:])]


def _leg_weights(spec: Spec, plans: list[ViaPlan], base: TubeDesign) -> list[float]:
    """The legs' shares of time under free timing: each leg's :func:`_path_length`; timed
    for the acceleration under a velocity bound, each leg's moves' durations when all the
    legs' moves share ``t_c`` (:func:`~.via.timed_moves`); with blended corners, those
    durations rebalanced by :func:`_blended_weights`."""
    timing = spec.tube.via_timing
    if timing == LENGTH_TIMING or spec.velocity_bound is None:
        return [_path_length(plan, timing) for plan in plans]
    moves = [_moves(plan) for plan in plans]
    seconds, _ = timed_moves(spec, [m for leg in moves for m in leg], spec.prescribed_time,
                             _leg_profile(spec))
    out, k = [], 0
    for leg in moves:
        out.append(sum(seconds[k:k + len(leg)]))
        k += len(leg)
    if spec.tube.via_corners == BLEND_CORNERS:
        return _blended_weights(spec, plans, base, out)
    return out


#: Samples of a leg on which :func:`_blended_weights` measures its peak acceleration.
LEG_SAMPLES = 2001


def _blended_weights(spec: Spec, plans: list[ViaPlan], base: TubeDesign,
                     seconds: list[float]) -> list[float]:
    """Each leg's time (``seconds``, the legs' moves at one common peak acceleration with
    stopped corners) times the square root of the peak acceleration of the leg's centre
    once its corners are blended in that time (:func:`_leg`, sampled): a leg whose corners
    blend less (a long move after short ones) gets more time, so that the blended legs ask
    about one peak acceleration (it falls as the square of a leg's time). Legs that do not
    move keep their time."""
    profile = _leg_profile(spec)
    peaks = [_peak_acceleration(base, _leg(plan, base, 0.0, duration, profile, spec),
                                duration)
             if duration > 0.0 and len(plan.lower) > 1 else 0.0
             for plan, duration in zip(plans, seconds)]
    moving = [k for k, peak in enumerate(peaks) if peak > 0.0]
    if not moving:
        return seconds
    weighted = {k: seconds[k] * float(np.sqrt(peaks[k])) for k in moving}
    # the moving legs share the time they had between them
    scale = sum(seconds[k] for k in moving) / sum(weighted.values())
    return [weighted[k] * scale if k in weighted else d for k, d in enumerate(seconds)]


def _peak_acceleration(base: TubeDesign, segments: list[ReachSegment],
                       duration: float) -> float:
    """The largest ``|d^2 c_i / dt^2|`` of the centre ``c`` of the reach tube of
    ``segments`` on ``[0, duration]`` over the axes, on :data:`LEG_SAMPLES` samples (the
    reference's ``rho_dot``, blended corners included, differenced), state units per
    second squared."""
    from ..tube.reference import reach_tube
    t = np.linspace(0.0, duration, LEG_SAMPLES)
    leg = replace(base, segments=tuple(segments), circumvents=(), prescribed_time=duration)
    _, _, rate_lower, rate_upper = reach_tube(leg, t)
    rate = 0.5 * (rate_lower + rate_upper)
    return float(np.max(np.abs(np.diff(rate, axis=0)) / (t[1] - t[0])))


def _leg_profile(spec: Spec) -> str:
    """The legs' profile: ``"cruise"``, or the spec's ``tube.via_profile`` when timed for
    the acceleration (module notes)."""
    return CRUISE if spec.tube.via_timing == LENGTH_TIMING else spec.tube.via_profile


def _leg(plan: ViaPlan, base: TubeDesign, t0: float, t1: float,
         profile: str = CRUISE, spec: Spec | None = None) -> list[ReachSegment]:
    """The segments (``profile``) of a leg's via boxes (:func:`_leg_path`) from ``t0`` to
    ``t1`` (seconds); with ``spec`` timed for the acceleration under a velocity bound, its
    moves timed again over the leg's duration (:func:`~.via.timed_moves`), else the
    plan's shares of ``[0, 1]`` scaled."""
    profiles: tuple[str, ...] = ()
    if (spec is not None and spec.tube.via_timing != LENGTH_TIMING
            and spec.velocity_bound is not None):
        seconds, chosen = timed_moves(spec, _moves(plan), t1 - t0, profile)
        times = [t0]
        for d in seconds:
            times.append(times[-1] + d)
        profiles = tuple(chosen)
    else:
        times = [t0 + (t1 - t0) * t for t in plan.times]
    times[0], times[-1] = t0, t1
    for k in range(1, len(times) - 1):
        times[k] = min(max(times[k], np.nextafter(times[k - 1], np.inf)), t1)
    if any(b <= a for a, b in zip(times, times[1:])):
        raise DesignError(f"no time for the via boxes between {t0:g} s and {t1:g} s",
                          kind=FailureKind.TASK, tried=base)
    timed = replace(plan, times=tuple(times), profiles=profiles, starts=())
    return list((blend_plan(timed, spec, profile) if spec is not None else timed)
                .segments(profile))


@dataclass(frozen=True)
class TaskPlan:
    """The visits a tasks' plan chose (docs/tasks.md, "Timing and order").

    Attributes
    ----------
    order : tuple of int
        Task indices (into ``spec.tasks``) in visit order.
    holds : tuple of (float, float)
        Per task in the spec's order: the interval over which ``rho`` holds its waypoint
        box, seconds.
    """

    order: tuple[int, ...]
    holds: tuple[tuple[float, float], ...]


def _centre(box: tuple) -> np.ndarray:
    return 0.5 * (np.array(box[0]) + np.array(box[1]))


def _boxes(spec: Spec, base: TubeDesign, order: tuple[int, ...],
           choice: tuple[int, ...]) -> list[tuple]:
    """The waypoint boxes (lower, upper tuples) in visit order, each centred as near as it
    may be to the previous one."""
    start = (tuple(base.initial_lower), tuple(base.initial_upper))
    out = []
    for k in order:
        lo, hi = waypoint_box(spec.tasks[k], choice[k], _centre(start), base)
        start = (tuple(float(v) for v in lo), tuple(float(v) for v in hi))
        out.append(start)
    return out


def _listed_holds(spec: Spec, order: tuple[int, ...], boxes: list[tuple], base: TubeDesign,
                  choice: tuple[int, ...]) -> list[tuple[float, float]] | None:
    """The fixed holds (module notes: the middle half of a reach window, a stay's whole
    window entered up to :data:`STAY_LEAD` early) when they follow one another in visit
    order and no stay task has a duration; else ``None``."""
    start = (tuple(base.initial_lower), tuple(base.initial_upper))
    leave = 0.0
    out = []
    for k, box in zip(order, boxes):
        task = spec.tasks[k]
        t0, t1 = task.window
        if task.duration is not None:
            return None
        if task.kind == STAY:
            arrive, until = t0 - min(STAY_LEAD, 0.25 * (t0 - leave)), t1
            if not arrive > leave and _within(start, task.boxes[choice[k]]):
                out.append((leave, until))      # held where the tube already is
                leave = until
                continue
        else:
            arrive, until = t0 + HOLD_LEAD * (t1 - t0), t1 - HOLD_LEAD * (t1 - t0)
        if not arrive > leave:
            return None
        out.append((arrive, until))
        start, leave = box, until
    return out if base.prescribed_time > leave else None


def _span(task: Task) -> tuple[float, float, float]:
    """Free timing: ``(earliest start, latest end, length)`` of a task's hold, seconds."""
    t0, t1 = task.window
    w = t1 - t0
    if task.kind == STAY:
        if task.duration is None or task.duration + 2 * STAY_LEAD > w:
            return t0 - STAY_LEAD, t1, w + STAY_LEAD
        return t0, t1, task.duration + 2 * STAY_LEAD
    hold = min(FREE_HOLD_SHARE * w, FREE_HOLD)
    return t0 + 0.5 * hold, t1 - 0.5 * hold, hold


def _centre_legs(base: TubeDesign, boxes: list[tuple]) -> list[float]:
    """The legs' lengths as their centres' distances (:func:`_distance`): from ``X-hat_0``
    through the waypoint boxes to ``T-hat``, state units."""
    centres = [_centre((base.initial_lower, base.initial_upper))]
    centres += [_centre(b) for b in boxes] + [_centre((base.target_lower, base.target_upper))]
    return [_distance(a, b) for a, b in zip(centres, centres[1:])]


def _free_holds(spec: Spec, order: tuple[int, ...], base: TubeDesign,
                legs: list[float]) -> tuple[list[tuple[float, float]] | None, str]:
    """The holds of free timing in visit order (module notes), or ``None`` and why not in
    the user's terms (which task, which window); ``legs``: the length of each leg (one
    more than the tasks: the last to the target), state units.

    With travel times at an estimated speed (the even speed, then faster), the earliest
    holds (each as soon as its window and the travel from the previous allow) and the
    latest (as late as the later ones and the target still allow) bound each hold's start;
    within them each starts when the even speed along the whole path would get there, so
    the legs' speeds stay near it (with free windows, every leg at the even speed: each
    leg's time in proportion to its length, all the time the holds leave used)."""
    length = sum(legs)
    spans = [_span(spec.tasks[k]) for k in order]
    spare = base.prescribed_time - sum(s[2] for s in spans)
    reason = ""
    for factor in SPEED_FACTORS:
        speed = max(factor * length / max(spare, MIN_LEG), 1e-12)
        travel = [max(d / speed, MIN_LEG) for d in legs]
        leave, early, previous = 0.0, [], "the start"
        for j, (k, (earliest, latest, hold)) in enumerate(zip(order, spans)):
            arrive = max(earliest, leave + travel[j])
            task = spec.tasks[k]
            if arrive + hold > latest + 1e-12:
                reason = (f"task {task.label} ({task.kind}, window [{task.window[0]:g}, "
                          f"{task.window[1]:g}] s) cannot be met after {previous} (left at "
                          f"{leave:.3g} s, about {travel[j]:.3g} s away at the fastest speed "
                          f"tried)")
                break
            early.append(arrive)
            leave, previous = arrive + hold, f"task {task.label}"
        else:
            if leave + travel[-1] > base.prescribed_time:
                reason = (f"no time to reach the target by {base.prescribed_time:g} s after "
                          f"{previous} (left at {leave:.3g} s)")
                continue
            late = [0.0] * len(spans)
            bound = base.prescribed_time - travel[-1]
            for j in reversed(range(len(spans))):
                late[j] = min(spans[j][1], bound) - spans[j][2]
                bound = late[j] - travel[j]
            share = spare / length if length > 0 else 0.0
            out, leave, elapsed = [], 0.0, 0.0
            for j, (earliest, _, hold) in enumerate(spans):
                even = elapsed + share * sum(legs[:j + 1])
                # late[j] >= max(earliest, leave + travel[j]): the earliest holds exist
                start = min(max(even, earliest, leave + travel[j]), late[j])
                out.append((start, start + hold))
                leave, elapsed = start + hold, elapsed + hold
            return out, ""
    return None, reason


def task_schedule(spec: Spec, base: TubeDesign, order: tuple[int, ...],
                  choice: tuple[int, ...], legs: list[float] | None = None
                  ) -> tuple[list[tuple], list[tuple[float, float]]]:
    """The waypoint boxes and holds of a visit order, both in visit order.

    The fixed holds (the middle half of each reach window, each stay's window) when they
    follow one another; else the free timing: each leg's time in proportion to its length
    where the windows allow (module notes).

    Parameters
    ----------
    spec : Spec
    base : TubeDesign
        The paper's tube of the spec (``X-hat_0``, ``T-hat``).
    order : tuple of int
        Task indices in visit order.
    choice : tuple of int
        One alternative per task, spec order.
    legs : list of float, optional
        Free timing: each leg's length (``len(order) + 1`` legs, the last to the target),
        state units; default the centres' distances (the via paths' lengths are longer
        around obstacles: :func:`plan_tasks` passes those, or, timed for the
        acceleration, the sums of their moves' :func:`~.via.move_weight`).

    Returns
    -------
    boxes : list of (tuple, tuple)
        Waypoint boxes' lower and upper corners, state units.
    holds : list of (float, float)
        Hold intervals, seconds.

    Raises
    ------
    DesignError
        Kind ``TASK``: no timing meets the windows in this order, naming the task and its
        window.
    """
    boxes = _boxes(spec, base, order, choice)
    holds = _listed_holds(spec, order, boxes, base, choice)
    if holds is None:
        holds, reason = _free_holds(spec, order, base,
                                    _centre_legs(base, boxes) if legs is None else legs)
        if holds is None:
            raise DesignError(reason, kind=FailureKind.TASK, tried=base)
    return boxes, holds


def _travel(spec: Spec, base: TubeDesign, order: tuple[int, ...],
            choice: tuple[int, ...] | None = None) -> float:
    """The centres' path length of a visit order (:func:`_distance` per move; default the
    first alternatives), state units."""
    choice = tuple(0 for _ in spec.tasks) if choice is None else choice
    return sum(_centre_legs(base, _boxes(spec, base, order, choice)))


def _feasible(spec: Spec, base: TubeDesign, order: tuple[int, ...],
              choice: tuple[int, ...] | None = None) -> bool:
    try:
        task_schedule(spec, base, order,
                      tuple(0 for _ in spec.tasks) if choice is None else choice)
    except DesignError:
        return False
    return True


def _two_opt(spec: Spec, base: TubeDesign, order: list[int]) -> list[int]:
    """2-opt on the estimated travel: reverse a stretch while it shortens the path."""
    best, cost = order, _travel(spec, base, tuple(order))
    improved = True
    while improved:
        improved = False
        for i in range(len(best) - 1):
            for j in range(i + 2, len(best) + 1):
                trial = best[:i] + best[i:j][::-1] + best[j:]
                c = _travel(spec, base, tuple(trial))
                if c < cost - 1e-12:
                    best, cost, improved = trial, c, True
    return best


def visit_orders(spec: Spec, base: TubeDesign) -> list[tuple[int, ...]]:
    """The visit orders to try, best first.

    ``[task_order] order = "listed"``: the spec's order alone. ``"any"``: up to
    :data:`EXACT_ORDERS` tasks every order whose windows admit a timing
    (:func:`task_schedule`), shortest estimated travel first, at most
    :data:`MAX_ORDERS`; beyond, the nearest-neighbour order by window start and travel,
    improved by 2-opt on the travel (a heuristic: another order may be shorter).

    Parameters
    ----------
    spec : Spec
    base : TubeDesign

    Returns
    -------
    list of tuple of int
        Task indices in visit order; the spec's order when no order admits a timing (its
        plan then says which task and window fail).
    """
    listed = tuple(range(len(spec.tasks)))
    if spec.task_order != "any" or len(spec.tasks) < 2:
        return [listed]
    if len(spec.tasks) <= EXACT_ORDERS:
        orders = sorted(permutations(listed), key=lambda o: (_travel(spec, base, o), o))
        good = [o for o in orders if _feasible(spec, base, o)][:MAX_ORDERS]
        return good or [listed]
    left, order = set(listed), []
    here = _centre((base.initial_lower, base.initial_upper))
    while left:
        k = min(left, key=lambda i: (spec.tasks[i].window[1],
                                     float(np.linalg.norm(_centre(
                                         (spec.tasks[i].boxes[0].lower,
                                          spec.tasks[i].boxes[0].upper)) - here)), i))
        order.append(k)
        left.discard(k)
        here = _centre((spec.tasks[k].boxes[0].lower, spec.tasks[k].boxes[0].upper))
    improved = tuple(_two_opt(spec, base, order))
    return [o for o in (improved, tuple(order)) if _feasible(spec, base, o)][:1] \
        or [tuple(order)]


def task_plans(spec: Spec, base: TubeDesign) -> list[tuple[tuple[int, ...], tuple[int, ...]]]:
    """The plans to try, best first: pairs of a visit order and an ``any_of`` combination.

    The candidate orders (the listed one; with ``order = "any"`` every order up to
    :data:`EXACT_ORDERS` tasks, else :func:`visit_orders`) with every combination of
    ``any_of`` alternatives (at most :data:`MAX_COMBINATIONS` pairs; beyond, the orders
    of :func:`visit_orders`), ranked by the centres' path length (the shortest asks the
    lowest speed of the tube) and kept when their windows admit a timing
    (:func:`task_schedule`), at most :data:`MAX_PLANS`.

    Parameters
    ----------
    spec : Spec
    base : TubeDesign
        The paper's tube of the spec (``X-hat_0``, ``T-hat``).

    Returns
    -------
    list of (tuple of int, tuple of int)
        ``(order, choice)``: task indices in visit order, and one alternative per task in
        the spec's order. The first candidate order with the first alternatives when no
        pair admits a timing (its plan then says which task and window fail).
    """
    listed = tuple(range(len(spec.tasks)))
    combos = list(islice(product(*(range(len(t.boxes)) for t in spec.tasks)),
                         MAX_COMBINATIONS))
    exact = (spec.task_order == "any" and 2 <= len(spec.tasks) <= EXACT_ORDERS
             and factorial(len(spec.tasks)) * len(combos) <= MAX_COMBINATIONS)
    orders = list(permutations(listed)) if exact else visit_orders(spec, base)
    combos = combos[:max(1, MAX_COMBINATIONS // len(orders))]
    ranked = sorted((_travel(spec, base, o, c), o, c) for o in orders for c in combos)
    good = [(o, c) for _, o, c in ranked if _feasible(spec, base, o, c)]
    return good[:MAX_PLANS] or [(orders[0], combos[0])]


def plan_tasks(spec: Spec, base: TubeDesign, choice: tuple[int, ...],
               order: tuple[int, ...] | None = None) -> tuple[TubeDesign, TaskPlan]:
    """``base`` with its reach tube through the tasks' waypoints (module notes).

    Parameters
    ----------
    spec : Spec
        With ``tasks``; the state space and obstacles.
    base : TubeDesign
        The paper's tube of the spec (:func:`~stt_codegen.design.search.base_design`):
        its first and last reach boxes are ``X-hat_0`` and ``T-hat``.
    choice : tuple of int
        One alternative per task, spec order (:func:`task_plans`).
    order : tuple of int, optional
        Task indices in visit order (:func:`visit_orders`); default the spec's order.

    Returns
    -------
    tube : TubeDesign
        ``cruise`` segments (``smoothstep`` timed for the acceleration: module notes), no
        circumvents; the gain is ``base``'s.
    plan : TaskPlan
        The visit order and each task's hold.

    Raises
    ------
    DesignError
        A leg has no via-point path (kinds ``NO_PASSAGE``, ``WALLED_OFF``), or the windows
        leave no timing (kind ``TASK``, naming the task and its window).
    """
    order = tuple(range(len(spec.tasks))) if order is None else order
    paths: dict[tuple, ViaPlan] = {}

    def path(start: tuple, goal: tuple, pending: list[int]) -> ViaPlan:
        key = (start, goal, tuple(pending))
        if key not in paths:
            paths[key] = _leg_path(_around(spec, pending), base, start, goal)
        return paths[key]

    # obstacles until a task: the legs up to that task's hold go around the box it sweeps
    until = [i for i, ob in enumerate(spec.moving_obstacles) if ob.until is not None]
    boxes = _boxes(spec, base, order, choice)
    starts = [(tuple(base.initial_lower), tuple(base.initial_upper))] + boxes
    goal = (tuple(base.target_lower), tuple(base.target_upper))
    pendings = [[i for i in until if spec.moving_obstacles[i].until not in order[:j]]
                for j in range(len(order))] + [[]]
    # free timing: each leg's time follows its via path's length (fixed holds: unused)
    legs = None
    if _listed_holds(spec, order, boxes, base, choice) is None:
        legs = _leg_weights(spec, [path(a, b, p)
                                   for a, b, p in zip(starts, boxes + [goal], pendings)], base)
    boxes, holds = task_schedule(spec, base, order, choice, legs)
    profile = _leg_profile(spec)
    start = starts[0]
    leave = 0.0
    segments: list[ReachSegment] = []
    for j, (box, (arrive, until_t)) in enumerate(zip(boxes, holds)):
        if arrive == leave:        # a stay held where the tube already is
            segments.append(ReachSegment(leave, until_t, *start, *start, CRUISE))
        else:
            segments += _leg(path(start, box, pendings[j]), base, leave, arrive, profile,
                             spec)
            segments.append(ReachSegment(arrive, until_t, *box, *box, CRUISE))
            start = box
        leave = until_t
    if not base.prescribed_time > leave:
        raise DesignError("no time to reach the target after the last task",
                          kind=FailureKind.TASK, tried=base)
    segments += _leg(path(start, goal, []), base, leave, base.prescribed_time, profile, spec)
    by_task = dict(zip(order, holds))
    plan = TaskPlan(order, tuple(by_task[k] for k in range(len(spec.tasks))))
    return replace(base, segments=tuple(segments), circumvents=()), plan
