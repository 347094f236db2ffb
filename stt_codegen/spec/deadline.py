"""A spec's prescribed time moved later with the ``[[tasks]]`` windows that end at it.

A task window that ends at ``prescribed_time`` says "by the deadline" (stlpy's
``F[0, T]``, ``G[0, T]``): a refusal that names a later ``prescribed_time`` for such a spec
means those windows to end at it too, and an obstacle that lasts until such a task
(``active_until``) lasts until then. Windows that end earlier are fixed times and stay.
:func:`with_deadline` is the spec so moved; the refusal's advice says so with
:data:`WINDOW_END` beside ``prescribed_time`` (docs/design.md, "Actuator limits").
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .loader import Spec
    from .motion import MovingObstacle

__all__ = ["WINDOW_END", "ending_windows", "fixed_in_time", "later_advice", "moved_words",
           "with_deadline"]

#: The advice key naming the end of the ``[[tasks]]`` windows that end at
#: ``prescribed_time``, given with ``prescribed_time`` when both move together.
WINDOW_END = "tasks.window_end"


def ending_windows(spec: "Spec") -> tuple[int, ...]:
    """The indices of ``spec``'s tasks whose window ends at its ``prescribed_time``.

    Parameters
    ----------
    spec : Spec

    Returns
    -------
    tuple of int
        In the tasks' order; empty without ``[[tasks]]``.
    """
    return tuple(k for k, task in enumerate(spec.tasks)
                 if task.window[1] == spec.prescribed_time)


def fixed_in_time(spec: "Spec") -> bool:
    """Whether a later ``prescribed_time`` leaves parts of ``spec`` fixed in absolute time
    that :func:`with_deadline` does not move: ``[[tasks]]`` none of whose windows ends at
    ``t_c``, a moving obstacle that does not last until such a task, or ``[target]
    any_of`` (whose boxes are searched one by one).

    Parameters
    ----------
    spec : Spec

    Returns
    -------
    bool
    """
    moved = set(ending_windows(spec))
    return bool((spec.tasks and not moved) or spec.target_any_of
                or any(ob.until not in moved for ob in spec.moving_obstacles))


def later_advice(spec: "Spec", later: float) -> dict[str, float]:
    """A refusal's advice for a later ``prescribed_time`` (``DesignError.advice``): with
    :data:`WINDOW_END` too where task windows end at the spec's, since the time was
    certified with them moved (:func:`with_deadline`)."""
    return {"prescribed_time": later, **({WINDOW_END: later} if ending_windows(spec) else {})}


def moved_words(spec: "Spec") -> str:
    """The words a refusal adds to a later ``prescribed_time`` it names: which windows
    end at it too (empty when none ends at ``spec``'s)."""
    return (f", with the [[tasks]] windows that end at {spec.prescribed_time:g} s ending at "
            "it too" if ending_windows(spec) else "")


def with_deadline(spec: "Spec", prescribed_time: float) -> "Spec":
    """``spec`` with ``prescribed_time`` and the task windows that end at its own (and the
    obstacles that last until those tasks) ending at the new one; each box of ``[target]
    any_of`` alike.

    Parameters
    ----------
    spec : Spec
    prescribed_time : float
        The new ``t_c``, s, not below the spec's.

    Returns
    -------
    Spec
        ``spec`` with only ``prescribed_time`` replaced when no window ends at it.

    Raises
    ------
    ValueError
        ``prescribed_time`` below the spec's (a window could then end after it).

    Examples
    --------
    >>> import stt_codegen as stt
    >>> spec = stt.Spec.from_dict({
    ...     "name": "two-visits", "prescribed_time": 20.0,
    ...     "state_space": {"lower": [0.0, 0.0], "upper": [10.0, 10.0]},
    ...     "initial": {"lower": [1.0, 1.0], "upper": [2.0, 2.0]},
    ...     "target": {"lower": [8.0, 8.0], "upper": [9.0, 9.0]},
    ...     "tasks": [{"kind": "reach", "window": [0.0, 20.0],
    ...                "lower": [1.0, 8.0], "upper": [2.0, 9.0]},
    ...               {"kind": "reach", "window": [0.0, 15.0],
    ...                "lower": [8.0, 1.0], "upper": [9.0, 2.0]}]})
    >>> [task.window for task in with_deadline(spec, 30.0).tasks]
    [(0.0, 30.0), (0.0, 15.0)]
    """
    old = spec.prescribed_time
    if prescribed_time < old:
        raise ValueError(f"prescribed_time {prescribed_time!r} is below the spec's {old!r}")
    moved = set(ending_windows(spec))
    tasks = tuple(replace(task, window=(task.window[0], float(prescribed_time)))
                  if k in moved else task for k, task in enumerate(spec.tasks))
    obstacles = tuple(_lasting(ob, old, float(prescribed_time))
                      if ob.until in moved and ob.active[1] == old else ob
                      for ob in spec.moving_obstacles)
    # each box of [target] any_of is a spec of its own, with the same tasks and obstacles
    alternatives = tuple((q, with_deadline(variant, prescribed_time))
                         for q, variant in spec.target_any_of)
    return replace(spec, prescribed_time=float(prescribed_time), tasks=tasks,
                   moving_obstacles=obstacles, target_any_of=alternatives)


def _lasting(ob: "MovingObstacle", old: float, new: float) -> "MovingObstacle":
    """The obstacle ``ob`` that lasts until ``old`` lasting until ``new``: a box that moves
    at a constant velocity moves on until then (its path's end as the loader writes it);
    a still box and a path (held after its last row) are only active longer."""
    if ob.motion == "velocity":
        t_on = ob.active[0]
        start, end = ob.centres
        share = (new - t_on) / (old - t_on)
        ob = replace(ob, times=(t_on, new),
                     centres=(start, tuple(a + (b - a) * share for a, b in zip(start, end))))
    return replace(ob, active=(ob.active[0], new))
