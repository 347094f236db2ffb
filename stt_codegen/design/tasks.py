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
  shortening and timing as a whole via design.

The certificate (:mod:`stt_codegen.design.certificate.tasks`) then proves each task for
every ``t``; the plan only makes it likely to pass. ``any_of`` tasks are tried in
:func:`alternatives` order (every combination, first alternatives first, at most
:data:`MAX_PLANS`); :func:`~stt_codegen.design.search.design_tube` keeps the first plan
whose tube passes its check.
"""

from __future__ import annotations

from dataclasses import replace
from itertools import islice, product

import numpy as np

from ..errors import DesignError
from ..spec.loader import Spec
from ..spec.tasks import STAY, Task
from ..tube.parameters import SMOOTHSTEP, ReachSegment, TubeDesign, paper_segments
from .failures import FailureKind
from .via import plan_via

__all__ = ["STAY_LEAD", "alternatives", "plan_tasks"]

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
#: Most combinations of ``any_of`` alternatives tried.
MAX_PLANS = 16


def alternatives(spec: Spec) -> list[tuple[int, ...]]:
    """The combinations of ``any_of`` alternatives to try, in order.

    Parameters
    ----------
    spec : Spec

    Returns
    -------
    list of tuple of int
        One index into ``task.boxes`` per task of ``spec.tasks``; the product of the
        alternatives in the spec's order (the first of each first), at most
        :data:`MAX_PLANS`.
    """
    return list(islice(product(*(range(len(t.boxes)) for t in spec.tasks)), MAX_PLANS))


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


def _leg(spec: Spec, base: TubeDesign, start: tuple, goal: tuple, t0: float,
         t1: float) -> list[ReachSegment]:
    """Via segments from box ``start`` at ``t0`` to box ``goal`` at ``t1`` (seconds)."""
    duration = t1 - t0
    leg = replace(base, prescribed_time=duration,
                  segments=paper_segments(*start, *goal, duration))
    plan = plan_via(spec, leg)
    times = [t0 + t for t in plan.times]
    times[0], times[-1] = t0, t1
    for k in range(1, len(times) - 1):
        times[k] = min(max(times[k], np.nextafter(times[k - 1], np.inf)), t1)
    if any(b <= a for a, b in zip(times, times[1:])):
        raise DesignError(f"no time for the via boxes between {t0:g} s and {t1:g} s",
                          kind=FailureKind.TASK, tried=base)
    return list(replace(plan, times=tuple(times)).segments())


def plan_tasks(spec: Spec, base: TubeDesign, choice: tuple[int, ...]) -> TubeDesign:
    """``base`` with its reach tube through the tasks' waypoints (module notes).

    Parameters
    ----------
    spec : Spec
        With ``tasks``; the state space and obstacles.
    base : TubeDesign
        The paper's tube of the spec (:func:`~stt_codegen.design.search.base_design`):
        its first and last reach boxes are ``X-hat_0`` and ``T-hat``.
    choice : tuple of int
        One alternative per task (:func:`alternatives`).

    Returns
    -------
    TubeDesign
        ``smoothstep`` segments, no circumvents; the gain is ``base``'s.

    Raises
    ------
    DesignError
        A leg has no via-point path (kinds ``NO_PASSAGE``, ``WALLED_OFF``), or two holds
        leave it no time (kind ``TASK``).
    """
    start = (tuple(base.initial_lower), tuple(base.initial_upper))
    leave = 0.0
    segments: list[ReachSegment] = []
    for task, q in zip(spec.tasks, choice):
        previous = 0.5 * (np.array(start[0]) + np.array(start[1]))
        lo, hi = waypoint_box(task, q, previous, base)
        box = (tuple(float(v) for v in lo), tuple(float(v) for v in hi))
        t0, t1 = task.window
        if task.kind == STAY:
            arrive, until = t0 - min(STAY_LEAD, 0.25 * (t0 - leave)), t1
        else:
            arrive, until = t0 + HOLD_LEAD * (t1 - t0), t1 - HOLD_LEAD * (t1 - t0)
        if task.kind == STAY and not arrive > leave and _within(start, task.boxes[0]):
            # a stay window from where the tube already is (e.g. from t = 0): hold it there
            segments.append(ReachSegment(leave, until, *start, *start, SMOOTHSTEP))
            leave = until
            continue
        if not arrive > leave:
            raise DesignError(f"task {task.label}: no time to reach its box before "
                              f"{arrive:g} s", kind=FailureKind.TASK, tried=base)
        segments += _leg(spec, base, start, box, leave, arrive)
        segments.append(ReachSegment(arrive, until, *box, *box, SMOOTHSTEP))
        start, leave = box, until
    goal = (tuple(base.target_lower), tuple(base.target_upper))
    if not base.prescribed_time > leave:
        raise DesignError("no time to reach the target after the last task",
                          kind=FailureKind.TASK, tried=base)
    segments += _leg(spec, base, start, goal, leave, base.prescribed_time)
    return replace(base, segments=tuple(segments), circumvents=())
