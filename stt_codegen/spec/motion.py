"""Obstacles that move or exist only for a while: the spec's ``active``, ``velocity``, ``path``.

A box obstacle with any of the keys ``active``, ``velocity`` or ``path`` is a *moving
obstacle* (the argument is docs/moving-obstacles.md): it is not in
``Spec.obstacles`` (the static boxes the design search avoids at every ``t``) but in
``Spec.moving_obstacles``, a :class:`MovingObstacle` each, which the design avoids where and
when it is.

* ``active = [t_on, t_off]`` (seconds): the obstacle exists for ``t_on <= t <= t_off``;
  omitted, always (``[0, inf)``).
* ``velocity`` (state units/s, on ``dims``): the box translates linearly from its
  ``lower``/``upper`` at ``t_on``. Without ``active`` it moves until it has left the state
  space for good: ``t_off`` is the time its trailing face crosses the state space's far
  boundary in the first dimension that separates them (:func:`leaving_time`; a moving
  box moving for ever would sweep an unbounded region, which the certificate, enclosing
  every ``t`` after the tube's last breakpoint at once, cannot take).
* ``path`` (rows ``[t, centre...]``, times increasing): the centre moves piecewise linearly
  between the rows and is held before the first and after the last; ``lower``/``upper``
  give the size and must be the box at the first row (their centre is the first row's).

Rules relating fields (the schema has checked each value): the lengths, ``t_on < t_off``,
``velocity`` xor ``path``, path times increasing; the box at ``t = 0`` (if active then)
misses the initial set; the box misses the target at every ``t >= t_c`` it is active (the
tube is in the target from ``t_c`` on). A moving box may leave the state space (the tube
stays inside it, so the part outside cannot meet the tube). Balls and polytopes cannot
move (the schema's message says to give a covering box).

This module is plain Python and numpy; the boxes it is given are any objects with
``lower``/``upper`` tuples (the loader's ``Box``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Sequence

import numpy as np

from ..errors import SpecError, number_text

__all__ = ["MovingObstacle", "check_moving", "is_moving", "moving_obstacle"]

#: Relative tolerance on a path's first centre against the centre of ``lower``/``upper``.
CENTRE_TOLERANCE = 1e-9


@dataclass(frozen=True)
class MovingObstacle:
    """A box obstacle that moves, or exists only on ``[t_on, t_off]``.

    The box at time ``t`` is ``centre(t) +- half_size`` on ``dims`` (it spans the state
    space in the other dimensions), present only while ``t_on <= t <= t_off``.

    Attributes
    ----------
    source : int
        Index of the spec's ``[[obstacles]]`` entry (as in messages: "obstacle 2").
    dims : tuple of int
        State dimensions of the box's bounds.
    half_size : tuple of float, length len(dims)
        Half the box's side on each of ``dims``, state units.
    times : tuple of float
        Knot times of the centre, increasing, seconds (one knot: a box that does not move).
    centres : tuple of tuple of float, shape (len(times), len(dims))
        The centre at each knot; linear between knots, held outside them.
    active : (float, float)
        ``(t_on, t_off)``, seconds; ``t_off`` may be ``inf``.
    motion : {"still", "velocity", "path"}
        How the spec gave it.
    until : int or None
        ``active_until = "Tk"``: index ``k - 1`` of the reach task whose meeting ends the
        box. It exists from ``t_on`` until a run first meets that task, and at the latest
        until the end of the task's window, which is ``t_off`` (docs/tasks.md, "Obstacles
        until a task").
    """

    source: int
    dims: tuple[int, ...]
    half_size: tuple[float, ...]
    times: tuple[float, ...]
    centres: tuple[tuple[float, ...], ...]
    active: tuple[float, float]
    motion: str
    until: int | None = None

    def ended_at(self, t_off: float) -> "MovingObstacle":
        """The same box, gone after ``min(t_off, active[1])`` (an obstacle until a task, once
        the task is met at ``t_off``)."""
        return replace(self, active=(self.active[0], min(self.active[1], float(t_off))))

    def centre(self, t: Any) -> np.ndarray:
        """The centre at times ``t`` (shape (N,)), shape (N, len(dims)); held outside the knots."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        c = np.array(self.centres)
        return np.stack([np.interp(t, self.times, c[:, k]) for k in range(len(self.dims))],
                        axis=1)

    def is_active(self, t: Any) -> np.ndarray:
        """Boolean (N,): the obstacle exists at each time."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        return (t >= self.active[0]) & (t <= self.active[1])

    def hull(self, t_start: Any, t_end: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The smallest box holding the obstacle over each ``[t_start, t_end]`` (on ``dims``).

        Parameters
        ----------
        t_start, t_end : array_like, shape (K,)
            Seconds; ``t_end`` may be ``inf``.

        Returns
        -------
        lower, upper : ndarray, shape (K, len(dims))
            The hull of the box's positions over the interval met with ``active``: the
            centre is linear between knots, so its range is that of the centre at the
            clipped ends and at the knots inside.
        present : ndarray of bool, shape (K,)
            The interval meets ``active`` (elsewhere the bounds are meaningless).
        """
        a = np.maximum(np.atleast_1d(np.asarray(t_start, dtype=float)), self.active[0])
        b = np.minimum(np.atleast_1d(np.asarray(t_end, dtype=float)), self.active[1])
        present = a <= b
        b = np.where(present, b, a)
        ca, cb = self.centre(a), self.centre(b)
        lo, hi = np.minimum(ca, cb), np.maximum(ca, cb)
        for tk, ck in zip(self.times, self.centres):
            inside = ((a < tk) & (tk < b))[:, None]
            lo = np.where(inside, np.minimum(lo, ck), lo)
            hi = np.where(inside, np.maximum(hi, ck), hi)
        half = np.array(self.half_size)
        return lo - half, hi + half, present

    def meeting_times(self, lower: Sequence[float], upper: Sequence[float], t_from: float,
                      t_to: float) -> list[tuple[float, float]]:
        """When the box meets the closed box ``[lower, upper]`` (full state dimension).

        Exact: on each linear piece of the motion, each dimension's overlap condition is
        linear in ``t``, so the times form an interval (touching counts as meeting).

        Returns
        -------
        list of (float, float)
            Closed time intervals within ``[t_from, t_to]`` met with ``active``, seconds,
            in order (empty: never).
        """
        t0, t1 = max(t_from, self.active[0]), min(t_to, self.active[1])
        if t0 > t1:
            return []
        cuts = [t0] + [t for t in self.times if t0 < t < t1] + [t1]
        out = []
        for a, b in zip(cuts, cuts[1:]):
            found = self._piece_meets(lower, upper, a, b)
            if found is not None:
                out.append(found)
        return out

    def _piece_meets(self, lower, upper, a: float, b: float) -> tuple[float, float] | None:
        """Times in ``[a, b]`` (one linear piece) at which the box meets ``[lower, upper]``."""
        ca = self.centre([a])[0]
        if math.isinf(b):            # held after the last knot: a still box on [a, inf)
            cb, span = ca, 1.0
        else:
            cb, span = self.centre([b])[0], b - a
        lo_t, hi_t = 0.0, 1.0        # fraction of the piece
        for k, d in enumerate(self.dims):
            h = self.half_size[k]
            # |c(s) - m| <= h + r with c(s) = ca + s (cb - ca): an interval of s
            m, r = 0.5 * (lower[d] + upper[d]), 0.5 * (upper[d] - lower[d])
            p, q = ca[k] - m, cb[k] - ca[k]
            reach = h + r
            if q == 0.0:
                if abs(p) > reach:
                    return None
                continue
            s1, s2 = sorted(((-reach - p) / q, (reach - p) / q))
            lo_t, hi_t = max(lo_t, s1), min(hi_t, s2)
            if lo_t > hi_t:
                return None
        if math.isinf(b):
            return (a, b)
        return (a + lo_t * span, a + hi_t * span)

    def signed_clearance(self, points: Any, t: Any) -> np.ndarray:
        """Distance of each state ``points[k]`` (shape (N, n)) at time ``t[k]`` outside the box,
        minus its depth inside; ``inf`` where the obstacle is not active."""
        y = np.atleast_2d(points)[:, list(self.dims)]
        t = np.atleast_1d(np.asarray(t, dtype=float))
        c = self.centre(t)
        half = np.array(self.half_size)
        gaps = np.maximum(c - half - y, y - c - half)
        outside = np.sqrt(np.sum(np.maximum(gaps, 0.0) ** 2, axis=1))
        value = np.where(np.any(gaps > 0, axis=1), outside, gaps.max(axis=1))
        return np.where(self.is_active(t), value, np.inf)


def is_moving(table: Any) -> bool:
    """Whether an ``[[obstacles]]`` entry (validated by the schema) moves or has ``active``.

    Parameters
    ----------
    table : BoxObstacle
        One validated ``[[obstacles]]`` table (any table kind: only ``active``, ``velocity``
        and ``path`` are read).

    Returns
    -------
    bool
        True if any of ``active``, ``velocity``, ``path`` is given.
    """
    return any(getattr(table, key, None) is not None for key in ("active", "velocity", "path"))


def leaving_time(lower: Sequence[float], upper: Sequence[float], velocity: Sequence[float],
                 space_lower: Sequence[float], space_upper: Sequence[float]) -> float:
    """How long a box translating at ``velocity`` takes to leave a box ``space`` for good.

    In a dimension with ``v > 0`` the box is past ``space`` once its lower face passes the
    space's upper face, after ``(space_upper - lower) / v``; with ``v < 0`` once its upper
    face passes the lower face, after ``(space_lower - upper) / v``. Disjoint in one
    dimension is disjoint, and in each moving dimension the separation only grows, so the
    box is gone from the first of these times on.

    Parameters
    ----------
    lower, upper : sequence of float, length m
        The box at the start, state units.
    velocity : sequence of float, length m
        State units per second.
    space_lower, space_upper : sequence of float, length m
        The state space on the box's dimensions, state units.

    Returns
    -------
    float
        Seconds from the start, ``>= 0``; ``inf`` if no entry of ``velocity`` is non-zero.
    """
    times = []
    for a, b, v, lo, hi in zip(lower, upper, velocity, space_lower, space_upper):
        if v > 0:
            times.append(max(0.0, (hi - a) / v))
        elif v < 0:
            times.append(max(0.0, (lo - b) / v))
    return min(times, default=math.inf)


def moving_obstacle(table: Any, name: str, source: int, dims: tuple[int, ...],
                    lower: tuple[float, ...], upper: tuple[float, ...],
                    space: tuple[tuple[float, ...], tuple[float, ...]] | None = None
                    ) -> MovingObstacle:
    """Build a :class:`MovingObstacle` from a box entry with motion keys, checking its rules.

    Parameters
    ----------
    table : BoxObstacle
        The validated entry (``active``, ``velocity``, ``path``).
    name : str
        ``"obstacles[j]"``, for messages.
    source : int
        ``j``.
    dims : tuple of int
        Its dimensions (checked by the loader).
    lower, upper : tuple of float
        Its box at ``t_on`` (checked non-empty by the loader).
    space : (tuple of float, tuple of float), optional
        The state space's bounds on ``dims``: a box with ``velocity`` and no ``active`` is
        active from 0 until it has left them (:func:`leaving_time`).

    Returns
    -------
    MovingObstacle

    Raises
    ------
    SpecError
        ``active`` not increasing; both ``velocity`` and ``path``; ``velocity`` without
        ``active`` that never leaves the state space (zero, or no ``space``); a wrong length; path times not increasing; a path not starting at the
        centre of ``lower``/``upper``.
    """
    m = len(dims)
    t_on, t_off = (0.0, math.inf) if table.active is None else tuple(table.active)
    label = getattr(table, "active_until", None)       # "Tk": active is [0, end of Tk's window]
    until = None if label is None else int(label[1:]) - 1
    if not t_on < t_off:
        raise SpecError(f"{name}.active", f"t_on = {t_on!r} must be less than t_off = {t_off!r}")
    if table.velocity is not None and table.path is not None:
        raise SpecError(f"{name}.path", "give velocity or path, not both")
    centre = tuple(0.5 * (a + b) for a, b in zip(lower, upper))
    half = tuple(0.5 * (b - a) for a, b in zip(lower, upper))
    if table.velocity is not None:
        v = tuple(table.velocity)
        if len(v) != m:
            raise SpecError(f"{name}.velocity", f"must have {m} entries (one per entry of "
                                                f"lower), got {len(v)}")
        if table.active is None:
            t_off = math.inf if space is None else leaving_time(lower, upper, v, *space)
            if math.isinf(t_off):
                raise SpecError(f"{name}.velocity", "a box that never leaves the state space "
                                "needs active = [t_on, t_off] (a zero velocity: omit "
                                "velocity for a box that stays)")
        end = tuple(c + vk * (t_off - t_on) for c, vk in zip(centre, v))
        return MovingObstacle(source, dims, half, (t_on, t_off), (centre, end), (t_on, t_off),
                              "velocity", until)
    if table.path is not None:
        rows = table.path
        for k, row in enumerate(rows):
            if len(row) != m + 1:
                raise SpecError(f"{name}.path", f"row {k} must have {m + 1} entries [t, centre "
                                                f"on {m} dimensions], got {len(row)}")
        times = tuple(float(r[0]) for r in rows)
        for k in range(1, len(times)):
            if not times[k] > times[k - 1]:
                raise SpecError(f"{name}.path", f"times must increase: row {k} has t = "
                                                f"{times[k]!r} after {times[k - 1]!r}")
        first = tuple(rows[0][1:])
        scale = max([1.0] + [abs(v) for v in centre])
        if any(abs(a - b) > CENTRE_TOLERANCE * scale for a, b in zip(first, centre)):
            raise SpecError(f"{name}.path", f"the first row's centre {_numbers(first)} is not "
                                            f"the centre {_numbers(centre)} of lower/upper")
        centres = tuple(tuple(float(v) for v in r[1:]) for r in rows)
        return MovingObstacle(source, dims, half, times, centres, (t_on, t_off), "path", until)
    return MovingObstacle(source, dims, half, (t_on,), (centre,), (t_on, t_off), "still",
                          until)


def _numbers(values) -> str:
    """A list of numbers as messages print them (:func:`~stt_codegen.errors.number_text`)."""
    return "[" + ", ".join(number_text(float(v)) for v in values) + "]"


def check_moving(obstacle: MovingObstacle, name: str, initial_set: Any, target_set: Any,
                 prescribed_time: float) -> None:
    """The moving box misses ``X_0`` at ``t = 0`` and ``T`` at every ``t >= t_c``.

    Parameters
    ----------
    obstacle : MovingObstacle
        The moving box.
    name : str
        Its field name in errors (``obstacles[i]``).
    initial_set : Box
        The initial set ``X_0`` (``lower``/``upper`` of shape (n,), state units).
    target_set : Box
        The target ``T`` (``lower``/``upper`` of shape (n,), state units).
    prescribed_time : float
        The prescribed time ``t_c``, s.

    Raises
    ------
    SpecError
        Field ``name``, saying when it meets which set.
    """
    if obstacle.meeting_times(initial_set.lower, initial_set.upper, 0.0, 0.0):
        raise SpecError(name, "meets the initial set at t = 0")
    met = obstacle.meeting_times(target_set.lower, target_set.upper, prescribed_time, math.inf)
    if met:
        a, b = met[0]
        raise SpecError(name, f"meets the target set on [{a:g}, {b:g}] s, after t_c = "
                              f"{prescribed_time:g} s (the tube must be in the target then)")
