"""The certificate's refinement loop: adaptive bisection of ``[0, inf)`` until proven.

The proof works on long intervals ``[t_a, t_b]`` of sampling instants and splits an
interval only where a margin is too thin; nothing is allocated per sample, and the last
interval ``[T, inf)`` is closed analytically (after ``T``, ``psi`` is constant, so
``alpha`` stays between its value at ``T`` and ``a*`` for ever). A certificate can resume
the partition and ``alpha`` bounds of a related one (:class:`~.report.CertificateState`).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ...spec.loader import Spec
from ...tube import reference
from ...tube.parameters import TubeDesign
from .enclosures import enclose, partition
from .implicit_step import alpha_ranges
from .narrowest import sharpen_narrowest
from .repropagate import repropagate, step_psi
from .tasks import task_margins
from .report import (MAX_MOVE_PER_SAMPLE, ROUNDING_MARGIN, Certificate, CertificateState, Enclosure,
                     certificate_report, point_tube)

__all__ = ["MAX_INTERVALS", "MIN_INTERVAL", "SPLIT", "WIDTH_REFINE_ROUNDS", "certify_tube"]

#: Most intervals the adaptive bisection may create before it gives up (the certificate
#: then fails with that reason); the work is linear in it.
MAX_INTERVALS = 200_000
#: A thin interval is cut into this many pieces (fewer rounds than bisection).
SPLIT = 4
#: Shortest interval the bisection creates, seconds (or one sampling period if longer):
#: at very high rates the enclosures need no finer time resolution than this.
MIN_INTERVAL = 1e-4
#: Rounds of finer ``alpha`` propagation for the narrowest width, at most
#: (:func:`_alpha_refinement`; the certificate's proof is complete before them).
WIDTH_REFINE_ROUNDS = 6
#: ... while the bound is below ``1 - WIDTH_REFINE_TOLERANCE`` of the upper bound of the
#: narrowest width, and each round raises it by at least ``WIDTH_REFINE_GAIN`` of that ...
WIDTH_REFINE_TOLERANCE = 0.15
WIDTH_REFINE_GAIN = 0.01
#: ... and at most this many intervals in the partition after them (a budget of its own:
#: the proof's ``max_intervals`` is the design search's, spent by then).
WIDTH_REFINE_INTERVALS = 2000


def _breakpoints(design: TubeDesign) -> tuple[list[int], int]:
    """Initial partition (sample indices) and ``T``'s index, after which ``psi`` is constant."""
    rate = design.rate_hz
    times = [0.0, design.prescribed_time]
    for s in design.segments:
        times += [s.start, s.end]
    for c in design.circumvents:
        times += [c.start, c.center, c.end]
    last = max(times)
    end = int(math.ceil(last * rate)) + 1
    points = {0, end}
    for t in times:
        if 0.0 < t < last:
            k = int(math.floor(t * rate))
            points.update((k, k + 1))
    return sorted(p for p in points if 0 <= p <= end), end


def _box_arrays(spec: Spec) -> list[tuple[np.ndarray, np.ndarray]]:
    """The corners of ``spec.obstacle_boxes()`` as arrays, once per certificate."""
    return [(np.array(box.lower), np.array(box.upper)) for box in spec.obstacle_boxes()]


def _failing(design: TubeDesign, spec: Spec, enc: Enclosure, selected, final: bool,
             boxes: list):
    """Boolean (K,) mask of intervals on which some property is not yet proven
    (``boxes``: :func:`_box_arrays`)."""
    bad = enc.width_min.min(axis=1) <= ROUNDING_MARGIN
    lo, hi = np.array(design.state_lower), np.array(design.state_upper)
    bad |= np.minimum(enc.lower_min - lo, hi - enc.upper_max).min(axis=1) < 0.0
    # a spec obstacle's separation (report.obstacle_separation) is its member boxes' least:
    # it is thin where one member's is
    for b in selected:
        box_lo, box_hi = boxes[b]
        gap = np.maximum(box_lo - enc.upper_max, enc.lower_min - box_hi).max(axis=1)
        bad |= gap <= ROUNDING_MARGIN
    if final:
        late = enc.t_end > design.prescribed_time
        t_lo, t_hi = np.array(spec.target_set.lower), np.array(spec.target_set.upper)
        inside = np.minimum(enc.lower_min - t_lo, t_hi - enc.upper_max).min(axis=1)
        bad |= late & (inside <= ROUNDING_MARGIN)
    bad |= enc.move_ratio > MAX_MOVE_PER_SAMPLE
    return bad


def certify_tube(design: TubeDesign, spec: Spec, obstacles: list[int] | None = None,
                 final: bool = True, max_intervals: int = MAX_INTERVALS,
                 resume: tuple[Certificate, float] | None = None) -> Certificate:
    """Prove the tube's safety properties for every ``t >= 0``.

    Parameters
    ----------
    design : TubeDesign
    spec : Spec
        For the state space, obstacles and target set.
    obstacles : list of int, optional
        Indices of ``spec.obstacle_boxes()`` to certify against; default all.
    final : bool
        Also prove ``inside target after t_c`` (a partial design of the search skips it).
    max_intervals : int
        Refinement budget; when it runs out, the properties not yet proven fail.
    resume : (Certificate, float), optional
        The certificate of a design whose tube equals this one before the given time
        (seconds), e.g. the same circumvents but one whose window opens then: its
        partition and ``alpha`` bounds before that time are reused (work shared across
        the candidates of the design search).

    Returns
    -------
    Certificate
        Properties ``non-empty``, ``initial state inside``, ``inside state space``,
        ``avoids obstacle j`` (one per spec obstacle), ``inside target after t_c`` and
        ``sampling rate`` (no bound moves more than :data:`MAX_MOVE_PER_SAMPLE` tube
        widths in one period), each with its smallest margin; with ``final``, one
        ``task Tk reach`` or ``task Tk stay`` per ``[[tasks]]`` entry after them
        (:mod:`.tasks`).
    """
    with reference.numpy_math():
        return _certify(design, spec, obstacles, final, max_intervals, resume)


def _certify(design: TubeDesign, spec: Spec, obstacles, final: bool,
             max_intervals: int, resume) -> Certificate:
    boxes = _box_arrays(spec)
    selected = list(range(len(boxes))) if obstacles is None else obstacles
    points, end = _breakpoints(design)
    dt = 1.0 / design.rate_hz
    min_steps = max(1, int(MIN_INTERVAL * design.rate_hz))
    budget_hit = False
    decisive = ""
    work = 0
    m = 2 * design.dimension
    previous = CertificateState()
    proven = None                           # (enclosure, state, Narrowest) once all holds
    width_rounds = 0
    reuse_limit = 0                         # intervals of `previous` that may be reused
    if resume is not None:
        parent, until = resume
        old = list(parent.state.points)
        # the parent's points up to `until`: its intervals that end by then carry over
        cut = int(np.searchsorted(np.array(old, dtype=float) * dt, until, side="right"))
        cut = min(cut, len(old) - 1)
        if cut >= 2 and old[-1] == end:
            points = sorted(set(old[:cut]) | {p for p in points if p > old[cut - 1]})
            previous = parent.state
            reuse_limit = cut - 1
    while True:
        part = _partition(design, points)     # i1 = -1: the tail [T, inf)
        i0, i1, t0, t1, steps, pieces = (part.i0, part.i1, part.t0, part.t1, part.steps,
                                         part.pieces)
        if proven is not None:
            # a cut of a proven partition: its bounds stay valid, follow the cuts only
            previous, done = repropagate(design, pieces, points, steps, proven[1])
            work += done
        else:
            # the intervals before the first new cut are unchanged: resume alpha after them
            same = next((q for q, (a, b) in enumerate(zip(points, previous.points)) if a != b),
                        min(len(points), len(previous.points)))
            keep = max(0, min(same - 1, len(previous.entries) - 1, reuse_limit))
            start = previous.entries[keep] if keep else ([0.0] * m, [0.0] * m)
            rows_lo, rows_hi, entries = alpha_ranges(design, pieces.psi_lo[keep:],
                                                      pieces.psi_hi[keep:], steps[keep:], start,
                                                      step_psi(design, i0[keep:], steps[keep:]))
            work += len(points) - keep
            previous = CertificateState(tuple(points),
                                        previous.alpha_lo[:keep] + tuple(rows_lo),
                                        previous.alpha_hi[:keep] + tuple(rows_hi),
                                        previous.entries[:keep] + tuple(entries))
        rows_lo, rows_hi = previous.alpha_lo, previous.alpha_hi
        reuse_limit = len(previous.entries)   # from now on `previous` is this tube's own
        a_min, a_max = np.maximum(np.array(rows_lo), 0.0), np.array(rows_hi)
        enc = enclose(design, pieces, a_min, a_max, t0, t1)
        bad = _failing(design, spec, enc, selected, final, boxes)
        length = np.where(i1 < 0, 0, i1 - i0)
        splittable = length >= max(2, 2 * min_steps)
        if final and not bad.any():
            # every property proven: sharpen the narrowest width (the gain comes from it)
            entry_lo = np.array([e[0] for e in previous.entries])
            entry_hi = np.array([e[1] for e in previous.entries])
            narrow = sharpen_narrowest(design, enc, steps, entry_lo, entry_hi)
            gained = (narrow.lower - proven[2].lower if proven is not None else math.inf)
            proven = (enc, previous, narrow)
            thin = narrow.interval_lower < (1.0 - WIDTH_REFINE_TOLERANCE) * narrow.upper
            split = _alpha_refinement(narrow.alpha_limited & thin, splittable)
            if (width_rounds >= WIDTH_REFINE_ROUNDS or not split.any()
                    or narrow.lower >= (1.0 - WIDTH_REFINE_TOLERANCE) * narrow.upper
                    or gained < WIDTH_REFINE_GAIN * narrow.upper
                    or len(points) + (SPLIT - 1) * int(split.sum()) > WIDTH_REFINE_INTERVALS):
                break
            width_rounds += 1
            points = _cut(points, i0, length, split)
            continue
        if proven is not None:
            break      # a finer alpha left a property unproven: keep the proven partition
        split = bad & splittable
        # a thin single-sample interval: its alpha may come in loose from a long predecessor
        single = bad & ~split
        pred = np.zeros_like(bad)
        pred[:-1] = single[1:]
        split |= pred & splittable
        # stop once a single-sample interval (with a single-sample predecessor or none)
        # fails: refining elsewhere cannot change the verdict
        failed = np.flatnonzero(single)
        if failed.size and np.any((failed == 0) | (length[np.maximum(failed - 1, 0)] <= 1)):
            break
        decisive = _surely_failing(design, spec, t0[bad], a_min[bad], a_max[bad], selected,
                                   boxes)
        if decisive:
            break             # the tube itself fails at an instant: no refinement helps
        if not split.any():
            break
        if len(points) + (SPLIT - 1) * int(split.sum()) > max_intervals:
            budget_hit = True
            break
        points = _cut(points, i0, length, split)
    narrowest = None
    if proven is not None:
        enc, previous, narrow = proven
        narrowest = (narrow.lower, narrow.time)
    certificate = certificate_report(design, spec, enc, selected, final, budget_hit,
                                     end * dt, max_intervals, narrowest)
    if final and spec.tasks:     # [[tasks]]: one property each, after the others
        certificate = replace(certificate, margins=certificate.margins
                              + task_margins(design, spec, enc))
    return replace(certificate, state=previous, decisive=decisive, work=work)


#: The last partition computed (by any certificate), with the tube and points it is of:
#: the design search certifies a complete tube right after the partial check of the same
#: tube (:func:`~stt_codegen.design.search.paper_design`), whose first partition is the
#: partial check's last one.
_LAST_PARTITION: list = [None]


def _partition(design: TubeDesign, points: list[int]):
    """:func:`~.enclosures.partition`, or the last one computed when of the same tube and
    points (its arrays are only read)."""
    last = _LAST_PARTITION[0]
    if last is not None and last[1] == points and last[0] == design:
        return last[2]
    part = partition(design, points)
    _LAST_PARTITION[0] = (design, list(points), part)
    return part


def _cut(points: list[int], i0: np.ndarray, length: np.ndarray, split: np.ndarray) -> list[int]:
    """``points`` with every interval of ``split`` cut into :data:`SPLIT` (sample indices)."""
    cuts = {int(a + (b * q) // SPLIT) for a, b in zip(i0[split], length[split])
            for q in range(1, SPLIT)}
    return sorted(set(points) | cuts)


def _alpha_refinement(limited: np.ndarray, splittable: np.ndarray) -> np.ndarray:
    """Intervals to cut so that ``alpha``'s bounds tighten where the width bound needs it.

    An *alpha-limited* interval (:class:`~.narrowest.Narrowest`) is cut if it is long
    enough (a narrower range of ``psi`` on each part narrows ``alpha``'s); one too short
    to cut has the nearest long interval before it cut instead, through which ``alpha``
    arrives with loose bounds.
    """
    split = limited & splittable
    long_before = np.where(splittable, np.arange(splittable.size), -1)
    nearest = np.maximum.accumulate(np.concatenate([[-1], long_before[:-1]]))
    before = nearest[np.flatnonzero(limited & ~splittable)]
    split[before[before >= 0]] = True
    return split


def _surely_failing(design: TubeDesign, spec: Spec, t: np.ndarray, a_min: np.ndarray,
                    a_max: np.ndarray, selected, boxes: list) -> str:
    """The property the tube certainly fails at one of the instants ``t`` ("" if none).

    With ``alpha`` in ``[a_min, a_max]``, the tube box at ``t`` contains the box for
    ``a_min`` (``gamma_L`` falls and ``gamma_U`` rises with ``alpha``) and is at most as
    wide as the box for ``a_max``. ``boxes``: :func:`_box_arrays`.
    """
    if not t.size:
        return ""
    both_l, both_u = point_tube(design, np.concatenate([t, t]), np.concatenate([a_min, a_max]))
    g_l, w_l = both_l[:t.size], both_l[t.size:]
    g_u, w_u = both_u[:t.size], both_u[t.size:]
    for b in selected:
        lo, hi = boxes[b]
        if np.any(np.all((g_l < hi) & (g_u > lo), axis=1)):
            return f"avoids obstacle {spec.obstacles[b].source}"
    if np.any(np.max(w_l - w_u, axis=1) > 0.0):
        return "non-empty"
    return ""


