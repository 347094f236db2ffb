"""Timed tasks judged on a closed-loop trajectory (the figures: :mod:`.task_plots`).

:func:`judge_tasks` reads each ``[[tasks]]`` entry (docs/tasks.md) on the simulated states
at the sampling instants and the Runge-Kutta points between them (the same points as the
collision check of :func:`~stt_codegen.runtime.simulate.simulate`) that fall inside the
task's window:

* **reach**: met when some point is in one of the task's boxes (closed box); ``time`` is
  the first such point, ``box`` the alternative it was in, ``margin`` the largest over
  the window's points of how deep the state is in its box (negative: how far out);
* **stay**: met when every point of the window is in the box (one of its ``any_of`` boxes,
  the same for all; ``box`` says which); ``time`` is the first point
  outside it (``None`` when met), ``margin`` the smallest depth;
* **stay with a duration** ``tau``: met when some run of consecutive points of the window,
  from its first to its last at least ``tau`` apart, is in the box; ``time`` is the start
  of the first such run, ``margin`` the largest over runs ``tau`` long of their smallest
  depth.

The depth of ``x`` in a box is ``min_i min(x_i - lower_i, upper_i - x_i)``, state units.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..spec.loader import Spec
from ..spec.tasks import STAY, Task

__all__ = ["TaskOutcome", "judge_tasks", "until_met"]


@dataclass(frozen=True)
class TaskOutcome:
    """One task judged on a trajectory (module notes).

    Attributes
    ----------
    task : str
        Its label, ``"T1"``...
    kind : {"reach", "stay"}
        The task's kind.
    window : list of float
        ``[t0, t1]``, seconds.
    met : bool
        Whether the run meets the task.
    time : float or None
        Reach: the first instant in a box; stay: the first instant out of it; seconds.
    margin : float or None
        State units (module notes); ``None`` when no point of the run lies in the window
        (a run shorter than the window's start).
    box : int or None
        Reach: the ``any_of`` alternative reached first (0 for a single box); stay: the one
        stayed in (the deepest when none is).
    """

    task: str
    kind: str
    window: list[float]
    met: bool
    time: float | None
    margin: float | None
    box: int | None = None


def _depth(x: np.ndarray, lower, upper) -> np.ndarray:
    return np.minimum(x - np.array(lower), np.array(upper) - x).min(axis=1)


def judge_task(task: Task, t: np.ndarray, x: np.ndarray) -> TaskOutcome:
    """Judge one task on states ``x`` (N, n) at times ``t`` (N,) seconds (module notes)."""
    t0, t1 = task.window
    inside = (t >= t0 - 1e-12) & (t <= t1 + 1e-12)
    tw, xw = t[inside], x[inside]
    window = [t0, t1]
    if not tw.size:
        return TaskOutcome(task.label, task.kind, window, False, None, None)
    depths = np.array([_depth(xw, b.lower, b.upper) for b in task.boxes])     # (B, K)
    if task.kind == STAY and task.duration is not None:
        return max((_judge_duration(task, tw, depths[b], b) for b in range(len(depths))),
                   key=lambda o: (o.met, -np.inf if o.margin is None else o.margin))
    if task.kind == STAY:
        b = int(np.argmax(depths.min(axis=1)))
        out = np.flatnonzero(depths[b] < 0.0)
        return TaskOutcome(task.label, task.kind, window, not out.size,
                           float(tw[out[0]]) if out.size else None, float(depths[b].min()),
                           task.any_of_index[b])
    hit = np.flatnonzero((depths >= 0.0).any(axis=0))
    first = int(hit[0]) if hit.size else None
    box = (task.any_of_index[int(np.argmax(depths[:, first] >= 0.0))]
           if first is not None else None)
    return TaskOutcome(task.label, task.kind, window, first is not None,
                       float(tw[first]) if first is not None else None,
                       float(depths.max()), box)


def _judge_duration(task: Task, tw: np.ndarray, depth: np.ndarray, box: int) -> TaskOutcome:
    """A stay task with a duration on the window's points ``tw`` and depths in
    ``task.boxes[box]`` (module notes)."""
    best, start = -np.inf, None
    for i in range(tw.size):
        j = int(np.searchsorted(tw, tw[i] + task.duration - 1e-12, side="left"))
        if j >= tw.size:
            break
        m = float(depth[i:j + 1].min())
        if m >= 0.0 and start is None:
            start = float(tw[i])
        best = max(best, m)
    return TaskOutcome(task.label, task.kind, list(task.window), start is not None, start,
                       None if best == -np.inf else best, task.any_of_index[box])


def judge_tasks(spec: Spec, t: np.ndarray, x: np.ndarray) -> list[TaskOutcome]:
    """:func:`judge_task` for every task of ``spec`` (empty without tasks).

    Parameters
    ----------
    spec : Spec
        The spec whose ``tasks`` are judged.
    t : ndarray, shape (N,)
        Seconds, increasing.
    x : ndarray, shape (N, n)
        The state at ``t``.

    Returns
    -------
    list of TaskOutcome
        In the spec's order.
    """
    return [judge_task(task, t, x) for task in spec.tasks]



def until_met(spec: Spec, outcomes: list[TaskOutcome]) -> tuple:
    """The spec's moving obstacles as a run meets them: one until a task
    (``MovingObstacle.until``) ends when the run first meets that task (it lasts to the end
    of the task's window when the run does not).

    Parameters
    ----------
    spec : Spec
        Its ``moving_obstacles``.
    outcomes : list of TaskOutcome
        :func:`judge_tasks` of the run.

    Returns
    -------
    tuple of MovingObstacle
    """
    return tuple(ob if ob.until is None or not outcomes[ob.until].met
                 else ob.ended_at(outcomes[ob.until].time)
                 for ob in spec.moving_obstacles)
