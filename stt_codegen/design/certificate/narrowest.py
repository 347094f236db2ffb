"""A tight certified lower bound of the tube's narrowest width (the width law (13)'s gain needs).

The gain of law (13) comes from ``gamma_d,min``, the narrowest width of the tube the
deployed controller enforces (``design/gain.py``). The certificate's partition bounds the
width on an interval by :func:`~.enclosures.width_lower_bound`; where ``rho``, ``beta`` or
``alpha`` move much on an interval, that bound is loose. This module sharpens it by branch
and bound in continuous time (proofs in ``docs/design.md``, "The narrowest width"):

* **Pieces.** An interval is cut into pieces; ``rho`` and ``beta`` get the piece's own
  ranges, and the deployed ``alpha`` a range of its own
  too: on an interval of one sampling period (where ``alpha`` is the linear interpolation
  of its two end values) between the linear interpolations of the bounds at the two ends;
  on a longer one between the two extreme constant-coefficient sequences over the piece's
  steps (:meth:`~.implicit_step.SequenceBounds.within`). :func:`~.enclosures.piece_widths`
  then bounds the width on the piece from below, for every ``t`` in it.
* **Upper bound.** The width grows with ``alpha`` (``gamma_L`` falls with ``alpha_L``,
  ``gamma_U`` rises with ``alpha_U``), so the width at an instant with ``alpha`` at its upper
  bound is at least the true width there, and the least of these, ``U``, is at least the
  true narrowest width.
* **Branching.** A piece whose lower bound is below ``(1 - WIDTH_TOLERANCE) U`` is cut
  into :data:`WIDTH_SPLIT` pieces while cutting can still raise it (the bound is below the
  width at its midpoint with ``alpha`` at its lower bound, by more than a quarter of the
  tolerance), within :data:`WIDTH_PIECE_BUDGET` pieces. A loose piece that cutting
  cannot help is *alpha-limited*: its interval's ``alpha`` bounds are too far apart, and
  the refinement loop (:mod:`.refine`) cuts that interval (or, when it is too short, the
  long interval before it) and propagates ``alpha`` again around the cuts
  (:mod:`.repropagate`).

The result is the least lower bound over all pieces and the tail ``[T, inf)``: a lower
bound of the width at every ``t >= 0``, never a sample minimum.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...tube import reference
from ...tube.parameters import TubeDesign
from .enclosures import piece_widths
from .implicit_step import SequenceBounds, sequence_bounds
from .report import Enclosure, point_tube

__all__ = ["Narrowest", "WIDTH_PIECE_BUDGET", "WIDTH_SPLIT", "WIDTH_TOLERANCE",
           "sharpen_narrowest"]

#: The narrowest width is sharpened until its lower bound is within this fraction of the
#: upper bound ``U`` (or cutting can no longer help, or the budget is spent).
WIDTH_TOLERANCE = 0.1
#: A loose piece is cut into this many pieces.
WIDTH_SPLIT = 8
#: Most pieces one sharpening creates (a few vectorized evaluations per round).
WIDTH_PIECE_BUDGET = 3000
#: Rounds of cutting at most.
WIDTH_MAX_ROUNDS = 12


@dataclass(frozen=True)
class Narrowest:
    """The sharpened narrowest width of a certified tube.

    Attributes
    ----------
    lower : float
        Certified lower bound of ``min_t min_i gamma_d_i(t)`` over every ``t >= 0``, state
        units.
    time : float
        Start of the piece where ``lower`` is attained, seconds.
    upper : float
        Upper bound of the same minimum (the width at an instant with ``alpha`` at its
        upper bound), state units: ``lower <= min width <= upper``.
    alpha_limited : ndarray of bool, shape (K,)
        Intervals of the partition on which a piece stays below ``(1 - WIDTH_TOLERANCE)
        upper`` because its ``alpha`` bounds are too far apart (cutting the piece cannot
        help; a finer ``alpha`` propagation can).
    interval_lower : ndarray, shape (K,)
        The least lower bound over each interval's pieces, state units.
    pieces : int
        Pieces evaluated (the work done).
    """

    lower: float
    time: float
    upper: float
    alpha_limited: np.ndarray
    interval_lower: np.ndarray
    pieces: int


def point_widths(design: TubeDesign, t: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """``min_i gamma_d_i``, the width of eq. (10)'s tube, at ``t`` (K,) for ``alpha`` (K, 2n)."""
    gamma_l, gamma_u = point_tube(design, t, alpha)
    return (gamma_u - gamma_l).min(axis=1)


def _piece_alpha(rows: np.ndarray, f0: np.ndarray, f1: np.ndarray, steps: np.ndarray,
                 enc: Enclosure, entry: tuple[np.ndarray, ...], inside: SequenceBounds,
                 slot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Range of ``alpha`` (P, 2n) on the pieces ``[f0, f1]``, fractions of their intervals ``rows``.

    On a one-period interval the deployed ``alpha`` is ``(1 - f) a_k + f a_{k+1}`` with
    ``a_k``, ``a_{k+1}`` in their bounds, so it lies between the interpolated bounds, whose
    extremes on ``[f0, f1]`` are at its ends. On a longer one of ``N`` periods it lies
    between its sample values at steps ``floor(f0 N) .. ceil(f1 N)``, which
    :meth:`~.implicit_step.SequenceBounds.within` bounds (``inside`` holds the intervals
    ``slot >= 0``). Both within the interval's range.

    Parameters
    ----------
    entry : (start_lo, start_hi, end_lo, end_hi)
        Bounds of ``alpha`` at each interval's start and end, (K, 2n) each.
    """
    a_min, a_max = enc.alpha_min[rows], enc.alpha_max[rows]
    n_steps = steps[rows]
    g0, g1 = f0[:, None], f1[:, None]
    start_lo, start_hi, end_lo, end_hi = (e[rows] for e in entry)
    lo = np.minimum((1 - g0) * start_lo + g0 * end_lo, (1 - g1) * start_lo + g1 * end_lo)
    hi = np.maximum((1 - g0) * start_hi + g0 * end_hi, (1 - g1) * start_hi + g1 * end_hi)
    many = n_steps > 1
    if many.any():
        j0 = np.floor(f0[many] * n_steps[many] * (1.0 + 1e-12))
        j1 = np.minimum(np.ceil(f1[many] * n_steps[many] * (1.0 - 1e-12)), n_steps[many])
        lo[many], hi[many] = inside.within(slot[rows[many]], np.minimum(j0, j1), j1)
    # within the interval's range: min(max(., a_min), a_max), numpy.clip's order
    return (np.minimum(np.maximum(lo, a_min), a_max),
            np.minimum(np.maximum(hi, a_min), a_max))


def sharpen_narrowest(design: TubeDesign, enc: Enclosure, steps: np.ndarray,
                      entry_lo: np.ndarray, entry_hi: np.ndarray) -> Narrowest:
    """Branch and bound on the narrowest width of a certified tube (see the module notes).

    Parameters
    ----------
    design : TubeDesign
    enc : Enclosure
        The certificate's final enclosure, ``K`` intervals, the last ``[T, inf)``.
    steps : ndarray, shape (K,)
        Sampling periods per interval (``inf`` for the tail).
    entry_lo, entry_hi : ndarray, shape (K, 2n)
        Bounds of the deployed ``alpha`` at each interval's start (``alpha`` at the end of
        interval ``k`` is the entry of ``k + 1``).

    Returns
    -------
    Narrowest
    """
    finite = np.isfinite(enc.t_end)
    count = int(finite.sum())
    width_all = enc.width_min.min(axis=1)
    tail_w, tail_t = list(width_all[~finite]), list(enc.t_start[~finite])
    limited = np.zeros(enc.t_start.size, dtype=bool)
    if count == 0:
        k = int(np.argmin(width_all))
        return Narrowest(float(width_all[k]), float(enc.t_start[k]), float(width_all[k]),
                         limited, width_all, 0)
    entry_lo = np.maximum(entry_lo, 0.0)
    entry = (entry_lo, entry_hi, np.vstack([entry_lo[1:], entry_lo[-1:]]),
             np.vstack([entry_hi[1:], entry_hi[-1:]]))
    par = np.flatnonzero(finite)
    # U from the intervals' own alpha ranges: the width at each midpoint with alpha at
    # its upper bound is at least the true width there
    mids = 0.5 * (enc.t_start[par] + enc.t_end[par])
    upper = float(point_widths(design, mids, enc.alpha_max[par]).min())
    low = width_all[par]
    loose = low < (1.0 - WIDTH_TOLERANCE) * upper
    done_low: list[np.ndarray] = [low[~loose]]
    done_t: list[np.ndarray] = [enc.t_start[par[~loose]]]
    done_par: list[np.ndarray] = [par[~loose]]
    # the pieces: parent interval, fractions [f0, f1] of it, width lower bound
    par, low = par[loose], low[loose]
    f0, f1 = np.zeros(par.size), np.ones(par.size)
    pieces = count
    stuck = np.zeros(0, dtype=int)
    # the sequence bounds inside the loose intervals of more than one period
    need = par[steps[par] > 1]
    slot = np.full(enc.t_start.size, -1)
    slot[need] = np.arange(need.size)
    inside = sequence_bounds(design, enc.psi_min[need], enc.psi_max[need], entry_lo[need],
                             entry_hi[need])

    def at(parents: np.ndarray, frac: np.ndarray) -> np.ndarray:
        t0, t1 = enc.t_start[parents], enc.t_end[parents]
        return t0 + (t1 - t0) * frac

    def alpha_of(parents: np.ndarray, a: np.ndarray, b: np.ndarray):
        return _piece_alpha(parents, a, b, steps, enc, entry, inside, slot)

    for _ in range(WIDTH_MAX_ROUNDS + 1):
        if not par.size:
            break
        mid = 0.5 * (f0 + f1)
        mid_lo, mid_hi = alpha_of(par, mid, mid)
        tm = at(par, mid)
        both = point_widths(design, np.concatenate([tm, tm]), np.vstack([mid_lo, mid_hi]))
        reachable, high = both[:par.size], both[par.size:]
        upper = min(upper, float(high.min()))
        loose = low < (1.0 - WIDTH_TOLERANCE) * upper
        helps = low < reachable - 0.25 * WIDTH_TOLERANCE * upper
        split = loose & helps
        stuck = np.concatenate([stuck, par[loose & ~helps]])
        keep = ~split
        done_low.append(low[keep])
        done_t.append(at(par[keep], f0[keep]))
        done_par.append(par[keep])
        if not split.any():
            par = par[:0]
            break
        if pieces + WIDTH_SPLIT * int(split.sum()) > WIDTH_PIECE_BUDGET:
            stuck = np.concatenate([stuck, par[split]])
            done_low.append(low[split])
            done_t.append(at(par[split], f0[split]))
            done_par.append(par[split])
            par = par[:0]
            break
        q = np.arange(WIDTH_SPLIT)
        span = (f1[split] - f0[split])[:, None]
        n0 = (f0[split][:, None] + span * q / WIDTH_SPLIT).ravel()
        n1 = (f0[split][:, None] + span * (q + 1) / WIDTH_SPLIT).ravel()
        n1[WIDTH_SPLIT - 1::WIDTH_SPLIT] = f1[split]            # the last piece ends exactly
        par = np.repeat(par[split], WIDTH_SPLIT)
        f0, f1 = n0, n1
        s0, s1 = at(par, f0), at(par, f1)
        s1 = np.maximum(s1, s0)
        low = piece_widths(design, s0, s1, alpha_of(par, f0, f1)[0]).min(axis=1)
        pieces += par.size
    else:
        # rounds used up (never in practice: 8^12 pieces an interval): the last pieces
        # count as they are
        done_low.append(low)
        done_t.append(at(par, f0))
        done_par.append(par)
    interval_lower = width_all.copy()
    finished = np.concatenate(done_par)
    interval_lower[finished] = np.inf
    np.minimum.at(interval_lower, finished, np.concatenate(done_low))
    all_low = np.concatenate(done_low + [np.array(tail_w)])
    all_t = np.concatenate(done_t + [np.array(tail_t)])
    k = int(np.argmin(all_low))
    limited[stuck] = True                   # repeated indices set the same flag
    return Narrowest(float(all_low[k]), float(all_t[k]), float(upper), limited, interval_lower,
                     pieces)
