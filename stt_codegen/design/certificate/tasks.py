"""The timed tasks' properties (``[[tasks]]``), proved for every ``t`` of their windows.

For a task with window ``[t0, t1]`` and the certificate's final partition (each interval
with a proven range of the deployed ``alpha``), the window is cut at sampling instants
into at most :data:`TASK_PIECES` pieces, plus the partition's own points, so that each
piece lies inside one partition interval. On a piece the tube is enclosed by
:func:`~.enclosures.enclose` from the ranges of ``rho``, ``beta`` and ``psi`` on the piece
and the ``alpha`` range of its partition interval (valid on any part of it): the tube box
lies in ``[lower_min, upper_max]`` at every ``t`` of the piece, not only at samples.

* **reach** (``task Tk reach``): some piece inside ``[t0, t1]`` on which the enclosure lies
  inside the task's box (any of its ``any_of`` boxes); the margin is the largest over
  pieces and boxes of ``min_i min(lower_min_i - box_lo_i, box_hi_i - upper_max_i)``.
* **stay** (``task Tk stay``): the pieces cover ``[t0, t1]`` (the first starts at or before
  ``t0``, the last ends at or after ``t1``) and on every one the enclosure lies inside the
  box (one and the same of its ``any_of`` boxes); the margin is the smallest (the largest
  over boxes).
* **stay with a duration** ``tau``: some run of consecutive pieces inside ``[t0, t1]``,
  together at least ``tau`` long, on every one of which the enclosure lies inside the box
  (one and the same ``any_of`` box); the margin is the largest over such runs (and boxes)
  of the smallest over the run's pieces.

A margin of at most :data:`~.report.ROUNDING_MARGIN` fails (docs/tasks.md, "The
certificate").
"""

from __future__ import annotations

import math

import numpy as np

from ...spec.loader import Spec
from ...spec.tasks import STAY, Task
from ...tube.parameters import TubeDesign
from .enclosures import enclose, piece_ranges
from .report import ROUNDING_MARGIN, Enclosure, Margin

__all__ = ["reach_certified_by", "task_margins"]

#: Pieces a window is cut into at most (besides the partition's points inside it).
TASK_PIECES = 200


def _sample_range(t0: float, t1: float, rate: float, cover: bool) -> tuple[int, int]:
    """Sample indices ``(a, b)``: ``[a/rate, b/rate]`` inside ``[t0, t1]`` or, with
    ``cover``, containing it."""
    a, b = math.floor(t0 * rate), math.ceil(t1 * rate)
    if cover:
        while a / rate > t0:
            a -= 1
        while b / rate < t1:
            b += 1
        return max(a, 0), b
    a, b = math.ceil(t0 * rate), math.floor(t1 * rate)
    while a / rate < t0:
        a += 1
    while b / rate > t1:
        b -= 1
    return a, b


def _inside(task: Task, lower_min: np.ndarray, upper_max: np.ndarray) -> np.ndarray:
    """(B, K): how far piece k's enclosure lies inside box b (negative: out)."""
    return np.array([np.minimum(lower_min - np.array(box.lower),
                                np.array(box.upper) - upper_max).min(axis=1)
                     for box in task.boxes])


def _pieces(design: TubeDesign, task: Task, enc: Enclosure
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The window's pieces ``[s0, s1]`` and how far each one's enclosure lies inside each of
    the task's boxes, (B, K); ``None`` when the window holds no sampling period."""
    rate = design.rate_hz
    t0, t1 = task.window
    a, b = _sample_range(t0, t1, rate, cover=task.kind == STAY and task.duration is None)
    if b <= a:
        return None
    points = np.rint(enc.t_start * rate).astype(np.int64)
    cuts = set(np.linspace(a, b, min(TASK_PIECES, b - a) + 1).round().astype(np.int64).tolist())
    cuts |= {int(p) for p in points if a < p < b}
    cuts = np.array(sorted(cuts), dtype=np.int64)
    s0, s1 = cuts[:-1] / rate, cuts[1:] / rate
    k = np.searchsorted(points, cuts[:-1], side="right") - 1
    sub = enclose(design, piece_ranges(design, s0, s1), enc.alpha_min[k], enc.alpha_max[k],
                  s0, s1)
    return s0, s1, _inside(task, sub.lower_min, sub.upper_max)


def reach_certified_by(design: TubeDesign, task: Task, enc: Enclosure) -> float | None:
    """The time by which every run inside the tube has met a reach task: the end of the
    first piece of its window on which the tube's enclosure lies inside one of its boxes
    (by more than :data:`~.report.ROUNDING_MARGIN`).

    Parameters
    ----------
    design : TubeDesign
    task : Task
        A ``reach`` task.
    enc : Enclosure
        A certificate's enclosure (its intervals and ``alpha`` ranges).

    Returns
    -------
    float or None
        Seconds; ``None`` when no piece is certified inside (or the task is a stay).
    """
    if task.kind == STAY:
        return None
    pieces = _pieces(design, task, enc)
    if pieces is None:
        return None
    _, s1, inside = pieces
    good = np.flatnonzero((inside > ROUNDING_MARGIN).any(axis=0))
    return float(s1[good[0]]) if good.size else None


def task_margin(design: TubeDesign, task: Task, enc: Enclosure) -> Margin:
    """The certified margin of one task over the partition of ``enc``.

    Parameters
    ----------
    design : TubeDesign
    task : Task
    enc : Enclosure
        The certificate's final enclosure (its intervals and ``alpha`` ranges).

    Returns
    -------
    Margin
        Named ``task.name``; state units; ``time`` is the start of the piece where the
        margin is reached (reach: largest; stay: smallest).
    """
    t0, t1 = task.window
    stay = task.kind == STAY
    pieces = _pieces(design, task, enc)
    if pieces is None:
        return Margin(task.name, False, -math.inf, t0, f"the window [{t0:g}, {t1:g}] s holds "
                      f"no sampling period at {design.rate_hz:g} Hz")
    s0, s1, inside = pieces
    if stay and task.duration is not None:
        return max((_duration_margin(task, inside[b], s0, s1, b) for b in range(len(inside))),
                   key=lambda margin: margin.margin)
    if stay:
        box = int(np.argmax(inside.min(axis=1)))
        q = int(np.argmin(inside[box]))
        m = float(inside[box, q])
        which = f" any_of[{task.any_of_index[box]}]" if len(task.boxes) > 1 else ""
        ok = m > ROUNDING_MARGIN
        detail = (f"the tube stays inside the box{which} over [{s0[0]:.4f}, {s1[-1]:.4f}] s "
                  f"(covers the window [{t0:g}, {t1:g}] s), margin >= {m:.6g} (smallest on "
                  f"[{s0[q]:.4f}, {s1[q]:.4f}] s)" if ok else
                  f"the tube may leave the box{which} on [{s0[q]:.4f}, {s1[q]:.4f}] s "
                  f"(margin {m:.3g})")
        return Margin(task.name, ok, m, float(s0[q]), detail)
    box, q = np.unravel_index(int(np.argmax(inside)), inside.shape)
    m = float(inside[box, q])
    ok = m > ROUNDING_MARGIN
    # the run of consecutive pieces inside the same box around the best one
    good = inside[box] > ROUNDING_MARGIN
    first, last = q, q
    while ok and first > 0 and good[first - 1]:
        first -= 1
    while ok and last + 1 < good.size and good[last + 1]:
        last += 1
    which = f" any_of[{task.any_of_index[box]}]" if len(task.boxes) > 1 else ""
    detail = (f"the tube lies inside the box{which} over [{s0[first]:.4f}, {s1[last]:.4f}] s "
              f"of the window [{t0:g}, {t1:g}] s, margin {m:.6g} (largest on "
              f"[{s0[q]:.4f}, {s1[q]:.4f}] s)" if ok else
              f"no piece of the window [{t0:g}, {t1:g}] s on which the tube is certified "
              f"inside the box{'es' if len(task.boxes) > 1 else ''} (best margin {m:.3g} "
              f"on [{s0[q]:.4f}, {s1[q]:.4f}] s)")
    return Margin(task.name, ok, m, float(s0[q]), detail)


def _duration_margin(task: Task, inside: np.ndarray, s0: np.ndarray,
                     s1: np.ndarray, box: int) -> Margin:
    """A stay task with a duration: the best run of consecutive pieces at least
    ``task.duration`` long (module notes) in ``task.boxes[box]``; ``inside`` (K,) per
    piece ``[s0, s1]``."""
    t0, t1 = task.window
    tau = task.duration
    best, run = -math.inf, (0, 0)
    for i in range(inside.size):
        j = int(np.searchsorted(s1, s0[i] + tau - 1e-12, side="left"))
        if j >= inside.size:
            break
        m = float(inside[i:j + 1].min())
        if m > best:
            best, run = m, (i, j)
    if best == -math.inf:
        return Margin(task.name, False, -math.inf, t0, f"the window [{t0:g}, {t1:g}] s holds "
                      f"no run of sampling periods {tau:g} s long")
    i, j = run
    ok = best > ROUNDING_MARGIN
    which = f" any_of[{task.any_of_index[box]}]" if len(task.boxes) > 1 else ""
    detail = (f"the tube stays inside the box{which} over [{s0[i]:.4f}, {s1[j]:.4f}] s (at least "
              f"{tau:g} s of the window [{t0:g}, {t1:g}] s), margin >= {best:.6g}" if ok else
              f"no {tau:g} s of the window [{t0:g}, {t1:g}] s over which the tube is "
              f"certified inside the box{which} (best margin {best:.3g} over [{s0[i]:.4f}, "
              f"{s1[j]:.4f}] s)")
    return Margin(task.name, ok, best, float(s0[i]), detail)


def task_margins(design: TubeDesign, spec: Spec, enc: Enclosure) -> tuple[Margin, ...]:
    """:func:`task_margin` of every task of ``spec``, in the spec's order (empty without
    tasks).

    Parameters
    ----------
    design : TubeDesign
        The tube.
    spec : Spec
        The spec; its ``tasks`` are judged.
    enc : Enclosure
        Bounds of ``gamma`` on the final partition.

    Returns
    -------
    tuple of Margin
        One ``task Tk reach`` or ``task Tk stay`` margin per task.
    """
    return tuple(task_margin(design, task, enc) for task in spec.tasks)

