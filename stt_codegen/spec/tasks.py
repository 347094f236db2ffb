"""Timed tasks of a spec (``[[tasks]]``): the rules that relate them to the other fields.

The schema (:mod:`stt_codegen.spec.schema`) has checked every key, type and sign of a
``[[tasks]]`` entry. :func:`build_tasks` checks what relates a task to the rest of the spec
(docs/tasks.md, "The spec") and turns the entries into :class:`Task` values:

* a task has either one box (``lower``/``upper``) or ``any_of`` (a list of boxes: a reach
  task is met in any of them, a stay task by staying in one of them);
* every box has one entry per state dimension (a dimension the task does not constrain is
  given the state space's bounds), is not empty (``lower < upper`` in every dimension), lies
  inside the state space and does not meet an obstacle (touching is allowed); an ``any_of``
  box that meets one is dropped (:attr:`Task.dropped` says which) as long as one remains;
* windows ``[t0, t1]`` satisfy ``0 <= t0 < t1 <= t_c``; they may overlap and come in any
  order (the design picks the visit times, and with ``[task_order] order = "any"`` the
  order; docs/tasks.md, "Timing and order");
* ``duration`` (stay only) satisfies ``0 < duration <= t1 - t0``; a duration equal to the
  window's length is the whole window;
* tasks need the via-point design (``tube.method`` ``"via"`` or ``"auto"``) and no
  ``[actuator]`` (not supported yet).

The first violation is a :class:`~stt_codegen.errors.SpecError` naming the field
(``tasks[1].window``). This module does not import the loader: boxes are :class:`TaskBox`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

from ..errors import SpecError, number_text

__all__ = ["STAY", "Task", "build_tasks"]

REACH = "reach"
STAY = "stay"


@dataclass(frozen=True)
class TaskBox:
    """A box of a task, ``prod_i [lower_i, upper_i]``, state units, length n each."""

    lower: tuple[float, ...]
    upper: tuple[float, ...]

    @property
    def center(self) -> tuple[float, ...]:
        """The box's centre, state units."""
        return tuple(0.5 * (a + b) for a, b in zip(self.lower, self.upper))

    @property
    def half_width(self) -> tuple[float, ...]:
        """Half the box's side in each dimension, state units."""
        return tuple(0.5 * (b - a) for a, b in zip(self.lower, self.upper))


@dataclass(frozen=True)
class Task:
    """One ``[[tasks]]`` entry, validated.

    Attributes
    ----------
    index : int
        Position in the spec's ``[[tasks]]`` (0-based); its label is ``T{index + 1}``.
    kind : {"reach", "stay"}
        ``"reach"``: the state is in one of :attr:`boxes` at some ``t`` of the window;
        ``"stay"``: the state is in the box for every ``t`` of the window.
    window : (float, float)
        ``[t0, t1]``, seconds.
    boxes : tuple of TaskBox
        One box, or the ``any_of`` alternatives in the spec's order, without those dropped.
    duration : float or None
        Stay only: inside the box over some interval of this length (seconds) inside the
        window; ``None``: the whole window.
    any_of_index : tuple of int
        The ``any_of`` index in the spec of each of :attr:`boxes` (``(0,)`` for one box).
    dropped : tuple of (int, int)
        The ``any_of`` boxes dropped because they meet an obstacle: their index and the
        ``[[obstacles]]`` entry each meets.
    """

    index: int
    kind: str
    window: tuple[float, float]
    boxes: tuple[TaskBox, ...]
    duration: float | None = None
    any_of_index: tuple[int, ...] = (0,)
    dropped: tuple[tuple[int, int], ...] = ()

    @property
    def held(self) -> float:
        """How long the task holds its box, seconds: the stay's duration (the window's
        length when none is given); 0 for a reach task."""
        if self.kind != STAY:
            return 0.0
        return self.duration if self.duration is not None else self.window[1] - self.window[0]

    @property
    def label(self) -> str:
        """``"T1"``, ``"T2"``, ... (the plots' and reports' name)."""
        return f"T{self.index + 1}"

    @property
    def name(self) -> str:
        """The certificate property's name, e.g. ``"task T1 reach"``."""
        return f"task {self.label} {self.kind}"


def _box(lower: Sequence[float] | None, upper: Sequence[float] | None, field: str, n: int,
         space: tuple[Sequence[float], Sequence[float]]) -> TaskBox:
    if lower is None or upper is None:
        raise SpecError(f"{field}.{'lower' if lower is None else 'upper'}", "missing")
    for key, value in (("lower", lower), ("upper", upper)):
        if len(value) != n:
            raise SpecError(f"{field}.{key}", f"must have {n} entries (one per state "
                            f"dimension; an unconstrained dimension takes the state space's "
                            f"bounds), got {len(value)}")
    for k, (a, b) in enumerate(zip(lower, upper)):
        if not a < b:
            raise SpecError(f"{field}.lower", f"lower[{k}] = {a!r} is not below "
                            f"upper[{k}] = {b!r}")
        if a < space[0][k] or b > space[1][k]:
            raise SpecError(field, f"dimension {k} [{a!r}, {b!r}] is not inside the state "
                            f"space [{number_text(space[0][k])}, {number_text(space[1][k])}]")
    return TaskBox(tuple(float(v) for v in lower), tuple(float(v) for v in upper))


def build_tasks(tables: Sequence, n: int, prescribed_time: float,
                space: tuple[Sequence[float], Sequence[float]],
                obstacles: Sequence[tuple[Sequence[float], Sequence[float], int]],
                method: str) -> tuple[Task, ...]:
    """Validate the ``[[tasks]]`` entries against the rest of the spec.

    Parameters
    ----------
    tables : sequence of TaskTable
        The schema-checked entries (``SpecDocument.tasks``).
    n : int
        State dimension.
    prescribed_time : float
        ``t_c``, seconds.
    space : (sequence of float, sequence of float)
        The state space's lower and upper corners, length n each.
    obstacles : sequence of (lower, upper, source)
        The obstacle boxes (full-dimensional, covering boxes of balls and polytopes
        included) and the index of the ``[[obstacles]]`` entry each comes from.
    method : str
        ``tube.method``.

    Returns
    -------
    tuple of Task
        In the spec's order (which is window order).

    Raises
    ------
    SpecError
        The first rule of the module notes that an entry breaks, naming the field
        (``tasks[k].window``, ``tasks[k].any_of[q]``, ...).
    """
    if not tables:
        return ()
    if method == "paper":
        raise SpecError("tube.method", "tasks need via points: 'via' or 'auto', not 'paper'")
    out: list[Task] = []
    for k, table in enumerate(tables):
        field = f"tasks[{k}]"
        t0, t1 = (float(v) for v in table.window)
        if not t0 < t1:
            raise SpecError(f"{field}.window", f"t0 = {t0!r} must be below t1 = {t1!r}")
        if t1 > prescribed_time:
            raise SpecError(f"{field}.window", f"ends at {t1!r} s, after prescribed_time "
                            f"{prescribed_time!r} s")
        duration = None if table.duration is None else float(table.duration)
        if duration is not None:
            if table.kind != STAY:
                raise SpecError(f"{field}.duration", "only a stay task takes a duration")
            if duration > t1 - t0:
                raise SpecError(f"{field}.duration", f"{duration!r} s is longer than the "
                                f"window [{t0!r}, {t1!r}] s")
            if duration == t1 - t0:
                duration = None
        has_box = table.lower is not None or table.upper is not None
        if table.any_of is not None:
            if has_box:
                raise SpecError(f"{field}.any_of", "give either lower/upper or any_of, "
                                "not both")
            boxes = tuple(_box(b.lower, b.upper, f"{field}.any_of[{q}]", n, space)
                          for q, b in enumerate(table.any_of))
            names = [f"{field}.any_of[{q}]" for q in range(len(boxes))]
        else:
            boxes = (_box(table.lower, table.upper, field, n, space),)
            names = [field]
        kept, dropped = [], []
        for q, (box, name) in enumerate(zip(boxes, names)):
            met = [source for lower, upper, source in obstacles
                   if all(a < d and c < b for a, b, c, d in
                          zip(box.lower, box.upper, lower, upper))]
            if met and table.any_of is None:
                raise SpecError(name, f"the task's box meets obstacle {met[0]}")
            if met:
                dropped.append((q, met[0]))
            else:
                kept.append(q)
        if not kept:
            raise SpecError(f"{field}.any_of", "every box meets an obstacle ("
                            + ", ".join(f"any_of[{q}]: obstacle {o}" for q, o in dropped)
                            + ")")
        out.append(Task(k, table.kind, (t0, t1), tuple(boxes[q] for q in kept), duration,
                        tuple(kept), tuple(dropped)))
    return tuple(out)
