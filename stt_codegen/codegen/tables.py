"""The spec's numbers as the rows of the generated code's ``const`` tables.

One block of tube parameters, one row per reach segment, one row per circumvent (sorted by
window start, the order of :func:`stt_codegen.tube.model.design_tables`), the state-space
bounds with their sign and number of circumvents. Values are printed by the caller's
``literal`` (exact C or Python text of the precision); every row is one line, so a
one-number change in a spec changes one line of each generated source.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..tube.model import design_tables, segment_rows
from ..tube.parameters import TubeDesign
from ..tube.pieces import PROFILE_NAMES

__all__ = ["PARAMETERS", "Tables", "design_table_rows", "max_open"]

#: Tube parameters in table order: (field, attribute of TubeDesign, comment).
PARAMETERS = (
    ("smoothness", "smoothness", "nu of the smooth max/min and of F_nu (eqs. (9)-(10)), 1/state units"),
    ("theta0", "theta0", "theta_0 of the trigger (11)"),
    ("mu", "mu", "mu of the trigger (11), state units"),
    ("kappa", "kappa", "kappa of the adaptive law (11), 1/s"),
    ("gain", "gain", "k of the control law (13)"),
)


@dataclass(frozen=True)
class Tables:
    """Printed table rows of one design (strings, in the target language's literal syntax).

    Attributes
    ----------
    parameters : list of (str, str, str)
        ``(field, value, comment)`` in :data:`PARAMETERS` order.
    bounds, signs : list of str
        2n entries ``[X; X-bar]`` and ``[+1; -1]``.
    members : list of int
        Number of circumvents on each of the 2n bounds.
    multi : list of int
        The bounds with several circumvents (``members > 1``), increasing.
    segments : list of dict
        ``start``, ``end``, ``profile`` (index into :data:`PROFILE_NAMES`), ``from``,
        ``to`` (2n lists of str).
    windows : list of dict
        ``start``, ``end``, ``center``, ``radius``, ``sharpness``, ``height``,
        ``max_end`` (the running maximum of the ends, for the search of open windows),
        ``bound`` (int), ``obstacle`` (int).
    max_open : int
        Largest number of windows open at one time (at least 1: a C array size).
    profiles : list of str
        Profile names used by the segments (those whose bodies are emitted).
    blended : bool
        Some segment starts before the previous one ends (a blended corner: the next
        segment's move is added where it has started).
    """

    parameters: list
    bounds: list
    signs: list
    members: list
    multi: list
    segments: list
    windows: list
    max_open: int
    profiles: list
    blended: bool = False


def _rounded(value: float, single: bool) -> float:
    return float(np.float32(value)) if single else float(value)


def max_open(intervals: list) -> int:
    """Largest number of intervals ``[start, end]`` sharing a point (>= 1), each widened by
    ``1e-6`` relative (plus ``1e-30``) on both sides: an upper bound on the windows open at
    one time even if the compiler rounds a table's decimal to a neighbouring float."""
    def widen(v: float, sign: float) -> float:
        return v + sign * (1e-6 * abs(v) + 1e-30)

    events = sorted([(widen(s, -1.0), 0) for s, _ in intervals]
                    + [(widen(e, 1.0), 1) for _, e in intervals])
    best = count = 0
    for _, kind in events:
        count += 1 if kind == 0 else -1
        best = max(best, count)
    return max(best, 1)


def design_table_rows(design: TubeDesign, literal: Callable[[float], str],
                      single: bool) -> Tables:
    """The table rows of ``design`` printed with ``literal``.

    Parameters
    ----------
    design : TubeDesign
    literal : callable
        Float -> source text (exact in the target precision).
    single : bool
        Whether the code computes in float32 (the open-window bound uses the rounded times).

    Returns
    -------
    Tables
        The rows of every table of the generated code.
    """
    tables = design_tables(design)
    parameters = [(field, literal(getattr(design, attr)), comment)
                  for field, attr, comment in PARAMETERS]
    segments = []
    for segment in tables.segments:
        lo, hi = segment_rows(design, segment)
        segments.append({"start": literal(segment.start), "end": literal(segment.end),
                         "profile": PROFILE_NAMES.index(segment.profile),
                         "from": [literal(v) for v in lo], "to": [literal(v) for v in hi]})
    windows, running = [], -np.inf
    for bound, c in tables.windows:
        running = max(running, c.end)
        windows.append({"start": literal(c.start), "end": literal(c.end),
                        "center": literal(c.center), "radius": literal(c.radius),
                        "sharpness": literal(c.sharpness), "height": literal(c.height),
                        "max_end": literal(running), "bound": bound, "obstacle": c.obstacle})
    intervals = [(_rounded(c.start, single), _rounded(c.end, single)) for _, c in tables.windows]
    members = [len(tables.members(b)) for b in range(len(tables.bounds))]
    return Tables(parameters, [literal(v) for v in tables.bounds],
                  [literal(v) for v in tables.signs], members,
                  [b for b, count in enumerate(members) if count > 1], segments, windows,
                  max_open(intervals),
                  [p for p in PROFILE_NAMES if any(s.profile == p for s in tables.segments)],
                  design.blends_corners)
