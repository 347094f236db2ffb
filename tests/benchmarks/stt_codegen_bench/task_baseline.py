"""The timed-task baseline: sequential A* with waiting, followed by the bench's tracker.

What a user without tubes would do for "visit A (or A') during [t0, t1], then B during
[t2, t3], ..., then the target": plan a path leg by leg on the A* grid of :mod:`.astar`
(the free space of :mod:`.planning`, obstacles and walls inflated by 0.2 m), from ``x(0)``
to the centre of the first task box, from there to the next, and from the last to the
target's centre; for an ``any_of`` task take the box whose leg is shortest. The tracker of
:mod:`.tracker` (carrot following at 1.5 m/s, then a proportional hold at the leg's end)
follows leg ``j`` until the middle of task ``j``'s window, where it switches to the next
leg: it waits at the box when it arrives early. With moving obstacles (which A* on the
static grid does not see), each leg may also wait at its start until its path is clear in
space-time (:mod:`.task_timing`: the earliest departure that still arrives by the middle
of the task's window, or by ``t_c``, and keeps the planners' margin from every moving
obstacle on the nominal schedule); without them nothing changes. The closed loop is
:func:`~stt_codegen.runtime.simulate.run_closed_loop`, which judges the tasks and
Definition 2.1 exactly as for the tube controller.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from stt_codegen.design.search import base_design
from stt_codegen.runtime.backends import STATUS_OK, backend_names, register_backend
from stt_codegen.runtime.simulate import SimulationResult, run_closed_loop
from stt_codegen.spec.loader import Spec
from .astar import RESOLUTION, grid_graph, grid_path
from .planning import FreeSpace
from .task_timing import departure
from .tracker import GOAL_GAIN, SPEED, PathTracker

__all__ = ["plan_timed", "track_timed"]

BACKEND = "bench-timed-tracker"


@dataclass(frozen=True)
class TimedPlan:
    """The legs of the baseline and when the tracker switches from one to the next.

    Attributes
    ----------
    legs : tuple of numpy.ndarray
        Leg ``j``: waypoints (K, 2), metres; ``None`` for the whole plan when some leg has
        no path (see ``reason``).
    switch : tuple of float
        Seconds: leg ``j + 1`` starts at ``switch[j]`` (the middle of task ``j``'s window,
        later when it waits for moving obstacles).
    choices : tuple of int
        The box taken per task (``any_of`` alternative).
    seconds : float
        Planning time (grid and every A* search), seconds.
    reason : str
        Empty when every leg has a path.
    start : float
        Seconds: leg 0 starts then (0 unless it waits for a moving obstacle); the robot
        holds ``x(0)`` before.
    clear : tuple of bool
        Per leg: whether its departure keeps clear of the moving obstacles on the nominal
        schedule (:func:`~.task_timing.departure`; ``True`` without moving obstacles).
    """

    legs: tuple | None
    switch: tuple[float, ...]
    choices: tuple[int, ...]
    seconds: float
    reason: str = ""
    start: float = 0.0
    clear: tuple[bool, ...] = ()


def _leg(graph, origin, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray | None, float]:
    """The A* path from ``a`` to ``b`` (K, 2) and its length, or ``(None, inf)``."""
    nodes = grid_path(graph, origin, a, b, RESOLUTION)
    if nodes is None:
        return None, math.inf
    path = np.vstack([a, nodes, b])
    return path, float(np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1)))


def plan_timed(spec: Spec) -> TimedPlan:
    """Plan the baseline's legs (module notes) for a 2-D spec with reach tasks.

    Parameters
    ----------
    spec : Spec
        2-D, its tasks all ``reach``.

    Returns
    -------
    TimedPlan
        ``reason`` is ``"no path found (leg j)"`` when a leg has no path on the grid.
    """
    begin = time.perf_counter()
    space = FreeSpace.of(spec)
    graph, origin = grid_graph(space)
    here = space.start
    legs, choices = [], []
    for j, task in enumerate(spec.tasks):
        options = [_leg(graph, origin, here, np.array(box.center)) for box in task.boxes]
        q = int(np.argmin([length for _, length in options]))
        if options[q][0] is None:
            return TimedPlan(None, (), (), time.perf_counter() - begin, f"no path found "
                             f"(leg {j})")
        legs.append(options[q][0])
        choices.append(q)
        here = np.array(task.boxes[q].center)
    last, _ = _leg(graph, origin, here, space.goal)
    if last is None:
        return TimedPlan(None, (), (), time.perf_counter() - begin,
                         f"no path found (leg {len(legs)})")
    legs.append(last)
    deadlines = [0.5 * (t.window[0] + t.window[1]) for t in spec.tasks]
    deadlines.append(spec.prescribed_time)
    leave, ok, may_start = [], [], 0.0
    for leg, deadline in zip(legs, deadlines):
        depart, fine = departure(leg, may_start, deadline, spec.moving_obstacles)
        leave.append(depart)
        ok.append(fine)
        may_start = deadline
    return TimedPlan(tuple(legs), tuple(leave[1:]), tuple(choices),
                     time.perf_counter() - begin, start=leave[0], clear=tuple(ok))


class TimedTracker:
    """The bench's :class:`~.tracker.PathTracker` on each leg in turn, switching at fixed
    times (a :class:`~stt_codegen.runtime.backends.Controller`)."""

    name = BACKEND

    def __init__(self, plan: TimedPlan) -> None:
        self.trackers = [PathTracker(leg) for leg in plan.legs]
        self.switch = list(plan.switch)
        self.start = plan.start
        self.home = np.asarray(plan.legs[0][0], float)

    def step(self, x, t, dt, alpha):
        """The controller step: the active leg's tracker command (before ``plan.start``, a
        proportional hold at ``x(0)``); ``alpha`` passed through."""
        x = np.asarray(x, float)
        if t < self.start:
            u = GOAL_GAIN * (self.home - x[:2])
            norm = float(np.linalg.norm(u))
            return (u if norm <= SPEED else u * (SPEED / norm),
                    np.asarray(alpha, float), STATUS_OK)
        j = sum(1 for s in self.switch if t >= s)
        return self.trackers[j].command(x), np.asarray(alpha, float), STATUS_OK


_PLANS: dict[str, TimedPlan] = {}


def _factory(design) -> TimedTracker:
    return TimedTracker(_PLANS.pop(design.name))


def track_timed(spec: Spec, plan: TimedPlan, seed: int) -> SimulationResult:
    """Run :class:`TimedTracker` on ``plan`` in closed loop (tasks and Definition 2.1
    judged by :func:`~stt_codegen.runtime.simulate.run_closed_loop`).

    Parameters
    ----------
    spec : Spec
        The problem (a spec with ``[[tasks]]``).
    plan : TimedPlan
        With legs.
    seed : int
        Disturbance seed (the tube controller's on the same problem).

    Returns
    -------
    SimulationResult
        The run, tasks judged; ``backend`` is the tracker's name.
    """
    if BACKEND not in backend_names():
        register_backend(BACKEND, _factory)
    design = base_design(spec)
    _PLANS[design.name] = plan
    try:
        return run_closed_loop(spec, design, backend=BACKEND, seed=seed)
    finally:
        _PLANS.pop(design.name, None)
