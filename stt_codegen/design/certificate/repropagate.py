"""Propagating ``alpha``'s bounds again where a partition was cut, and only there.

Every bound the certificate computes for the deployed ``alpha`` holds, whatever partition it
was computed on. So when a proven partition is cut further (to sharpen the narrowest width,
:mod:`.narrowest`), the bounds of the intervals it keeps stay valid, and the bounds at an
interval's start may be intersected with new ones. :func:`repropagate` follows the new
intervals with :func:`~.implicit_step.alpha_ranges` and carries on through the kept ones
only while the bounds it brings are tighter, by more than :data:`TIGHTER`, than the kept
ones; then it copies the kept intervals' bounds up to the next new interval. The work is
that of the cuts, not of the whole partition.
"""

from __future__ import annotations

import numpy as np

from ...tube import reference
from ...tube.parameters import TubeDesign
from .enclosures import Pieces
from .implicit_step import EXACT_STEPS, Propagation
from .report import CertificateState

__all__ = ["repropagate", "step_psi"]

#: Bounds brought into a kept interval replace its own where they are tighter by more than
#: this fraction of its own bounds' spread (plus ``1e-12``) in some component.
TIGHTER = 0.01
#: A short interval's steps use ``psi`` at their instants, widened by this (state units)
#: for rounding (:func:`step_psi`).
STEP_PSI_SLACK = 1e-9


def step_psi(design: TubeDesign, i0: np.ndarray, steps: np.ndarray) -> list:
    """``psi`` and ``theta`` at the instants the steps of each short interval use.

    The deployed step from ``t_k`` to ``t_{k+1}`` takes ``psi(t_{k+1})``, a value, where the
    interval's range of ``psi`` would widen ``alpha``'s bounds wherever ``psi`` moves fast.
    The value is widened by :data:`STEP_PSI_SLACK` (plus ``1e-12`` relative) for the
    rounding of the instant and of ``psi``.

    Parameters
    ----------
    design : TubeDesign
        The tube.
    i0 : ndarray of int, shape (K,)
        Sample index of each interval's start.
    steps : ndarray, shape (K,)
        Sampling periods per interval (``inf`` for the tail).

    Returns
    -------
    list
        Per interval: ``(psi_lo, psi_hi, theta_lo, theta_hi)``, nested lists (steps, 2n),
        for one of at most :data:`~.implicit_step.EXACT_STEPS` steps; ``None`` for a
        longer one (the argument ``step_psi`` of :func:`~.implicit_step.alpha_ranges`).
    """
    short = np.flatnonzero(steps <= EXACT_STEPS)
    out: list = [None] * steps.size
    if not short.size:
        return out
    counts = steps[short].astype(int)
    index = np.repeat(i0[short], counts) + np.concatenate([np.arange(1, c + 1) for c in counts])
    psi = reference.conflict_distance(design, index / design.rate_hz)
    slack = STEP_PSI_SLACK + 1e-12 * np.abs(psi)
    rows = [a.tolist() for a in (psi - slack, psi + slack, reference.trigger(design, psi + slack),
                                 reference.trigger(design, psi - slack))]
    first = 0
    for k, count in zip(short.tolist(), counts.tolist()):
        out[k] = tuple(r[first:first + count] for r in rows)
        first += count
    return out


def _tighter(lo: list, hi: list, old_lo: list, old_hi: list) -> bool:
    return any(a - c > TIGHTER * (d - c) + 1e-12 or d - b > TIGHTER * (d - c) + 1e-12
               for a, b, c, d in zip(lo, hi, old_lo, old_hi))


def repropagate(design: TubeDesign, pieces: Pieces, points: list[int], steps: np.ndarray,
                old: CertificateState) -> tuple[CertificateState, int]:
    """``alpha``'s bounds on a cut partition, from a proven one (see the module notes).

    Parameters
    ----------
    design : TubeDesign
        The tube.
    pieces : Pieces
        Of the new partition (``psi`` ranges).
    points : list of int
        The new partition's sample indices (every old point among them).
    steps : ndarray, shape (K,)
        Sampling periods per new interval (``inf`` for the tail).
    old : CertificateState
        The proven partition's bounds.

    Returns
    -------
    state : CertificateState
        The new partition with its bounds.
    work : int
        Intervals whose bounds were computed.
    """
    count = len(points)
    old_at = {p: k for k, p in enumerate(old.points)}
    ends = list(points[1:]) + [None]
    old_ends = list(old.points[1:]) + [None]
    kept = [p in old_at and old_ends[old_at[p]] == e for p, e in zip(points, ends)]
    # the coefficients of every interval (vectorized; only the followed ones are used)
    run = Propagation(design, pieces.psi_lo, pieces.psi_hi, steps,
                      step_psi(design, np.array(points), steps))
    rows_lo: list = [None] * count
    rows_hi: list = [None] * count
    entries: list = [None] * count
    a_lo, a_hi = [0.0] * (2 * design.dimension), [0.0] * (2 * design.dimension)
    work = 0
    for k in range(count):
        if kept[k]:
            j = old_at[points[k]]
            o_lo, o_hi = old.entries[j]
            lo = [max(a, b) for a, b in zip(a_lo, o_lo)]
            hi = [min(a, b) for a, b in zip(a_hi, o_hi)]
            if not _tighter(lo, hi, o_lo, o_hi):
                # nothing new comes in: the kept interval's own bounds
                rows_lo[k], rows_hi[k], entries[k] = old.alpha_lo[j], old.alpha_hi[j], (o_lo, o_hi)
                if j + 1 < len(old.entries):
                    a_lo, a_hi = list(old.entries[j + 1][0]), list(old.entries[j + 1][1])
                continue
            a_lo, a_hi = lo, hi
        entries[k] = (list(a_lo), list(a_hi))
        rows_lo[k], rows_hi[k] = run.advance(k, a_lo, a_hi)
        work += 1
    return CertificateState(tuple(points), tuple(rows_lo), tuple(rows_hi), tuple(entries)), work
