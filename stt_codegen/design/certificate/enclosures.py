"""Interval enclosures of the tube's pieces: ranges of ``rho``, the bumps, ``beta``, ``psi``.

Vectorized over the ``K`` intervals ``[t0, t1]`` of a partition (proofs in
``docs/design.md``): ``rho`` is monotone on every reach segment; each bump of eqs.
(7)-(8) rises up to its centre and falls after it, ``|b_dot|`` unimodal on each
half-window; eq. (9) is monotone in every bump and the smooth max/min of eq. (10) in every
argument. :func:`enclose` composes them with a range of ``alpha`` into an
:class:`~.report.Enclosure`.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

from ...tube import reference
from ...tube.parameters import LOWER, TANH, TubeDesign
from .report import Enclosure

__all__ = ["Pieces", "bump_ranges", "circumvent_range", "enclose", "enclose_later",
           "enclose_tube", "partition",
           "piece_ranges", "piece_widths", "reach_range", "width_lower_bound"]


def _tanh_rate_peak() -> float:
    lo, hi = 0.5, 1.0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if (1.0 + mid) * math.tanh(mid) < 1.0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


#: ``w*``, the root of ``(1 + w) tanh w = 1``: the tanh profile's rate peaks at
#: ``tau = w* / (1 + w*)`` (see ``verify.lemma.reach_rate_bound``).
_W_STAR = _tanh_rate_peak()


def _bump_peaks(sharpness: float) -> float:
    """``z*`` where ``|b_dot|`` peaks, as a fraction of the half-window (``verify.lemma``)."""
    return math.sqrt(((1.0 - sharpness) + math.sqrt((1.0 - sharpness) ** 2 + 3.0)) / 3.0)


def _clip(value, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """``numpy.clip(value, low, high)``, ``min(max(value, low), high)``, without its Python
    wrapper (which costs more than the two ufuncs on small arrays)."""
    return np.minimum(np.maximum(value, low), high)


def bump_ranges(c, t0: np.ndarray, t1: np.ndarray) -> tuple[np.ndarray, ...]:
    """Range of one bump and of its rate ``b_dot`` on each interval, shape (K,) each.

    The bump rises up to its centre and falls after it; ``b_dot`` is 0 at the window's
    edges and centre and monotone between them and its peaks ``m -+ r z*``, so its
    extremes on an interval are at the ends or at those points inside.

    Parameters
    ----------
    c : Circumvent
        One circumvent (its ``center``, ``radius`` in s and ``sharpness``).
    t0, t1 : ndarray, shape (K,)
        Ends of the intervals, s, ``t0 <= t1``.

    Returns
    -------
    low, high, rate_min, rate_max : ndarray, shape (K,)
    """
    z = _bump_peaks(c.sharpness)
    points = [t0, t1, _clip(c.center, t0, t1)] + [
        _clip(c.center + sign * c.radius * z, t0, t1) for sign in (-1, 1)]
    values, rates = reference.bump(np.concatenate(points), c.center, c.radius, c.sharpness)
    values = values.reshape(len(points), -1)
    rates = rates.reshape(len(points), -1)
    low = np.minimum(values[0], values[1])
    high = np.where((t0 <= c.center) & (c.center <= t1), 1.0, np.maximum(values[0], values[1]))
    return low, high, rates.min(axis=0), rates.max(axis=0)


def circumvent_range(design: TubeDesign, t0: np.ndarray, t1: np.ndarray,
                     ranges: list | None = None):
    """Ranges of ``beta_L`` and ``beta_U`` (eq. (9)) over each interval, shape (K, n) each.

    ``beta_L`` is non-decreasing and ``beta_U`` non-increasing in every bump value, so
    eq. (9) at the ends of the bumps' ranges gives the ends of theirs.

    Parameters
    ----------
    design : TubeDesign
        The tube (its circumvents and state-space bounds).
    t0, t1 : ndarray, shape (K,)
        Ends of the intervals, s.
    ranges : list, optional
        :func:`bump_ranges` of each of ``design.circumvents`` on these intervals, if
        already computed.

    Returns
    -------
    (lower_min, lower_max), (upper_min, upper_max) : ndarray, shape (K, n)
        Ranges of ``beta_L`` and ``beta_U``, state units.
    """
    t0, t1 = np.atleast_1d(t0), np.atleast_1d(t1)
    if ranges is None:
        ranges = [bump_ranges(c, t0, t1) for c in design.circumvents]
    lower_min, upper_max, _ = reference.circumvent_from_bumps(design, [r[0] for r in ranges],
                                                              t0.size, weights=False)
    lower_max, upper_min, _ = reference.circumvent_from_bumps(design, [r[1] for r in ranges],
                                                              t0.size, weights=False)
    return (lower_min, lower_max), (upper_min, upper_max)


def _circumvent_rate(design: TubeDesign, t0: np.ndarray, ranges: list):
    """Ranges of ``beta_L_dot`` and ``beta_U_dot`` per interval, shape (K, n) each, from the
    :func:`bump_ranges` of each circumvent.

    ``beta_L_dot = sum_j w_j B^j b_dot_j`` with weights ``w_j`` in ``[0, 1]``
    (:func:`~stt_codegen.tube.reference.open_bump_sum`), ``beta_U_dot`` its negative.

    Returns
    -------
    (lower_min, lower_max), (upper_min, upper_max)
    """
    n = design.dimension
    lo_l, hi_l = np.zeros((t0.size, n)), np.zeros((t0.size, n))
    lo_u, hi_u = np.zeros((t0.size, n)), np.zeros((t0.size, n))
    for c, (_, _, r_min, r_max) in zip(design.circumvents, ranges):
        i = c.dimension
        if c.side == LOWER:
            lo_l[:, i] += c.height * np.minimum(r_min, 0.0)
            hi_l[:, i] += c.height * np.maximum(r_max, 0.0)
        else:
            lo_u[:, i] -= c.height * np.maximum(r_max, 0.0)
            hi_u[:, i] -= c.height * np.minimum(r_min, 0.0)
    return (lo_l, hi_l), (lo_u, hi_u)


def reach_range(design: TubeDesign, t0: np.ndarray, t1: np.ndarray, rates: bool = True):
    """Ranges of ``rho_L``, ``rho_U``, of their rates and the least ``rho_U - rho_L`` per interval.

    ``rho`` is monotone on each segment; its rate has one sign there and is unimodal
    (peak at ``tau = w*/(1+w*)`` for ``"tanh"``, ``1/2`` for ``"smoothstep"``; for
    ``"cruise"``, ``"scurve"`` and ``"glide"`` non-decreasing up to ``1/2`` and
    non-increasing after, ``1/2`` a point of the cruise's and the glide's plateau and the
    S-curve's peak) and 0 at a segment's end; evaluated at a boundary it is the right
    limit, so 0 joins the range of an interval with a segment end inside. The reach box's width
    ``rho_U - rho_L = (U_from - L_from) + ((U_to - L_to) - (U_from - L_from)) p(tau)`` is
    monotone on each segment too, so its least value on an interval is at its ends or at a
    segment boundary inside: a box that moves keeps its width, however far it moves. A tube
    that blends corners: :func:`_blended_reach_range`.

    Parameters
    ----------
    design : TubeDesign
        The tube (its reach segments).
    t0, t1 : ndarray, shape (K,)
        Ends of the intervals, s.
    rates : bool
        Also the rates' ranges (else ``None`` in their place).

    Returns
    -------
    (lower_min, lower_max), (upper_min, upper_max), ((rate_lower_min, rate_lower_max),
    (rate_upper_min, rate_upper_max)), width_min
        Each (K, n).
    """
    if design.blends_corners:
        return _blended_reach_range(design, t0, t1, rates)
    edges = sorted({s.start for s in design.segments} | {s.end for s in design.segments})
    peaks = [s.start + s.duration * (_W_STAR / (1.0 + _W_STAR) if s.profile == TANH else 0.5)
             for s in design.segments] if rates else []
    # each interval's ends, and every edge (and peak) strictly inside an interval, by
    # interval: an edge outside clips to an end, whose values are among the ends' already
    inner = np.array(edges + peaks)[:, None]
    which, where = np.nonzero((t0 < inner) & (inner < t1))
    edge = which < len(edges)
    k = t0.size
    rho_l, rho_u, rate_l, rate_u = reference.reach_tube(
        design, np.concatenate([t0, t1, inner[which, 0]]), rates)
    at, values = where[edge], 2 * k + np.flatnonzero(edge)

    def extremes(v, intervals, inside):
        """Per interval, the least and largest of ``v`` at its ends and of ``inside`` (its
        values at the points inside, by ``intervals``)."""
        low, high = np.minimum(v[:k], v[k:2 * k]), np.maximum(v[:k], v[k:2 * k])
        np.minimum.at(low, intervals, inside)
        np.maximum.at(high, intervals, inside)
        return low, high

    def value_range(v):
        return extremes(v, at, v[values])

    lowest_width = value_range(rho_u - rho_l)[0]
    if not rates:
        return value_range(rho_l), value_range(rho_u), None, lowest_width
    ends = np.zeros(t0.shape, dtype=bool)
    for seg in design.segments:
        ends |= (t0 < seg.end) & (seg.end <= t1)
    zero = np.where(ends[:, None], 0.0, np.nan)

    def span(rate):
        low, high = extremes(rate, where, rate[2 * k:])
        return np.fmin(low, zero), np.fmax(high, zero)

    return (value_range(rho_l), value_range(rho_u), (span(rate_l), span(rate_u)),
            lowest_width)


def _blended_reach_range(design: TubeDesign, t0: np.ndarray, t1: np.ndarray, rates: bool):
    """:func:`reach_range` of a tube that blends corners (two segments move it at once).

    ``rho(t) = rho(t0) + sum_j (to_j - from_j) (p_j(t) - p_j(t0))`` on ``[t0, t1]``, where
    every profile ``p_j`` is non-decreasing in ``t``: term ``j`` lies between 0 and ``(to_j -
    from_j) (p_j(t1) - p_j(t0))``, so the interval sum of the terms bounds ``rho``, the width
    likewise. ``rho_dot = sum_j (to_j - from_j) p_j_dot(t)``, each ``p_j_dot >= 0`` unimodal
    on its segment and 0 outside: its range on an interval is between its values at the
    ends (the smaller one, or 0 with an edge of the segment inside) and, with its peak
    inside, the peak. ``rho(t0)`` is the deployed composition's value; the rest is exact
    arithmetic on monotone pieces, as :func:`reach_range`'s.
    """
    n = design.dimension
    segs = design.segments
    rho_l, rho_u, _, _ = reference.reach_tube(design, t0, rates=False)
    low_l, high_l, low_u, high_u = (rho_l.copy(), rho_l.copy(), rho_u.copy(), rho_u.copy())
    width = rho_u - rho_l
    rate = [np.zeros((t0.size, n)) for _ in range(4)]       # lower (min, max), upper (min, max)
    for seg in segs:
        p0, d0 = reference.segment_progress(seg, t0)
        p1, d1 = reference.segment_progress(seg, t1)
        step = (p1 - p0)[:, None]
        move_l = np.array(seg.lower_to) - np.array(seg.lower_from)
        move_u = np.array(seg.upper_to) - np.array(seg.upper_from)
        for low, high, move in ((low_l, high_l, move_l), (low_u, high_u, move_u)):
            change = move * step
            low += np.minimum(change, 0.0)
            high += np.maximum(change, 0.0)
        width += np.minimum((move_u - move_l) * step, 0.0)
        if not rates:
            continue
        peak_at = seg.start + seg.duration * (_W_STAR / (1.0 + _W_STAR) if seg.profile == TANH
                                              else 0.5)
        top = np.maximum(d0, d1)
        inside = (t0 < peak_at) & (peak_at < t1)
        if inside.any():
            top[inside] = np.maximum(top[inside],
                                     reference.segment_progress(seg, [peak_at])[1][0])
        edge = ((t0 < seg.start) & (seg.start < t1)) | ((t0 < seg.end) & (seg.end <= t1))
        bottom = np.where(edge, 0.0, np.minimum(d0, d1))
        for k, move in ((0, move_l), (2, move_u)):
            a, b = move * bottom[:, None], move * top[:, None]
            rate[k] += np.minimum(a, b)
            rate[k + 1] += np.maximum(a, b)
    spans = ((rate[0], rate[1]), (rate[2], rate[3])) if rates else None
    return (low_l, high_l), (low_u, high_u), spans, width


# --------------------------------------------------------------------------- intervals


@dataclass(frozen=True)
class Pieces:
    """What an interval contributes, vectorized over the K intervals of a partition.

    Attributes
    ----------
    rho_l, rho_u : tuple of ndarray
        ``(min, max)`` of ``rho_L`` and ``rho_U`` (eq. (4)) on each interval, (K, n) each,
        state units.
    beta_l, beta_u : tuple of ndarray
        ``(min, max)`` of ``beta_L`` and ``beta_U`` (eq. (9)), (K, n) each, state units.
    rho_rate : tuple or None
        ``((min, max) of rho_L_dot, (min, max) of rho_U_dot)``, (K, n) each, state units/s;
        None where not needed (:func:`piece_widths`).
    beta_rate : tuple or None
        The same for ``beta_L_dot``, ``beta_U_dot``.
    psi_lo, psi_hi : ndarray or None
        Range of ``psi`` (eq. (11)), shape (K, 2n), state units.
    rho_width : ndarray
        Least ``rho_U - rho_L`` on each interval, shape (K, n), state units.
    """

    rho_l: tuple
    rho_u: tuple
    beta_l: tuple
    beta_u: tuple
    rho_rate: tuple
    beta_rate: tuple
    psi_lo: np.ndarray
    psi_hi: np.ndarray
    #: least ``rho_U - rho_L`` on the interval, (K, n)
    rho_width: np.ndarray


@dataclass(frozen=True)
class Partition:
    """A cut partition of the samples: interval ``q`` is ``[i0[q] dt, i1[q] dt]`` (``i1 =
    -1``: the tail ``[T, inf)``, ``t1 = inf``), ``steps`` sampling periods long (``inf`` for
    the tail), with the ranges of the tube's pieces on it."""

    i0: np.ndarray
    i1: np.ndarray
    t0: np.ndarray
    t1: np.ndarray
    steps: np.ndarray
    pieces: Pieces


def partition(design: TubeDesign, points: list[int]) -> Partition:
    """The intervals between consecutive sample indices ``points`` (the last one opens the
    tail) and the pieces' ranges on them (:func:`piece_ranges`; the tail's at its start).

    Parameters
    ----------
    design : TubeDesign
        The tube (its rate sets the sample times ``i / rate_hz``).
    points : list of int
        Increasing sample indices, the cuts.

    Returns
    -------
    Partition
        ``len(points)`` intervals, the last one the tail ``[t_last, inf)``.
    """
    dt = 1.0 / design.rate_hz
    i0 = np.array(points)
    i1 = np.append(i0[1:], -1)
    t0 = i0 * dt
    t1 = np.where(i1 < 0, np.inf, i1 * dt)
    return Partition(i0, i1, t0, t1, np.where(i1 < 0, np.inf, (i1 - i0).astype(float)),
                     piece_ranges(design, t0, np.where(i1 < 0, t0, t1)))


def piece_ranges(design: TubeDesign, t0: np.ndarray, t1: np.ndarray) -> Pieces:
    """Ranges of ``rho``, ``beta``, their rates and ``psi`` (eq. (11)) on each ``[t0, t1]``.

    Parameters
    ----------
    design : TubeDesign
        The tube.
    t0, t1 : ndarray, shape (K,)
        Ends of the intervals, s, ``t0 <= t1``.

    Returns
    -------
    Pieces
        The ranges on the ``K`` intervals.
    """
    rho_l, rho_u, rho_rate, rho_width = reach_range(design, t0, t1)
    # the bumps' ranges serve both beta's range and its rate's
    bumps = [bump_ranges(c, t0, t1) for c in design.circumvents]
    beta_l, beta_u = circumvent_range(design, t0, t1, bumps)
    beta_rate = _circumvent_rate(design, t0, bumps)
    psi_lo = np.concatenate([beta_u[0] - rho_l[1], rho_u[0] - beta_l[1]], axis=1)
    psi_hi = np.concatenate([beta_u[1] - rho_l[0], rho_u[1] - beta_l[0]], axis=1)
    return Pieces(rho_l, rho_u, beta_l, beta_u, rho_rate, beta_rate, psi_lo, psi_hi, rho_width)


def piece_widths(design: TubeDesign, t0: np.ndarray, t1: np.ndarray,
                 alpha_min: np.ndarray) -> np.ndarray:
    """Lower bound of ``gamma_U - gamma_L`` on each ``[t0, t1]`` for ``alpha >= alpha_min``.

    The bound of :func:`enclose` (``width_min``) without the rest: the larger of
    ``min gamma_U - max gamma_L`` and :func:`width_lower_bound`, each monotone in ``alpha``.

    Parameters
    ----------
    design : TubeDesign
        The tube.
    t0, t1 : ndarray, shape (K,)
        Seconds.
    alpha_min : ndarray, shape (K, 2n)

    Returns
    -------
    ndarray, shape (K, n)
    """
    n = design.dimension
    nu = design.smoothness
    rho_l, rho_u, _, rho_width = reach_range(design, t0, t1, rates=False)
    beta_l, beta_u = circumvent_range(design, t0, t1)
    pieces = Pieces(rho_l, rho_u, beta_l, beta_u, None, None, None, None, rho_width)
    lower_max = reference.smooth_max_pair(rho_l[1] - alpha_min[:, :n], beta_l[1], nu)
    upper_min = -reference.smooth_max_pair(-(rho_u[0] + alpha_min[:, n:]), -beta_u[0], nu)
    return np.maximum(upper_min - lower_max, width_lower_bound(design, pieces, alpha_min))


def _softplus(d: np.ndarray, nu: float) -> np.ndarray:
    """``(1/nu) ln(1 + exp(nu d))``, increasing: ``max~(a, b) = a + softplus(b - a)``."""
    return np.logaddexp(0.0, nu * d) / nu


def width_lower_bound(design: TubeDesign, pieces: Pieces, alpha_min: np.ndarray) -> np.ndarray:
    """A lower bound of ``gamma_U - gamma_L`` on each interval that does not lose the box's move.

    With ``s(d) = (1/nu) ln(1 + exp(nu d))``, eq. (10) reads ``gamma_L = (rho_L - alpha_L) +
    s(beta_L - rho_L + alpha_L)`` and ``gamma_U = (rho_U + alpha_U) - s(rho_U + alpha_U -
    beta_U)``, so exactly

        gamma_U - gamma_L = (rho_U - rho_L) + [alpha_U - s(rho_U + alpha_U - beta_U)]
                                            + [alpha_L - s(beta_L - rho_L + alpha_L)].

    Each bracket increases with its ``alpha`` (slope ``1 - s' >= 0``) and its ``beta``'s
    distance, and falls with its ``rho`` bound; the first term is bounded by
    ``rho_U - rho_L`` itself (:func:`reach_range`). On a segment without circumvents the
    brackets are tiny, so the bound is the reach box's width, whatever the box's move.

    Parameters
    ----------
    design : TubeDesign
        The tube (its smoothness ``nu``).
    pieces : Pieces
    alpha_min : ndarray, shape (K, 2n)
        Lower bounds of ``alpha`` on the intervals.

    Returns
    -------
    ndarray, shape (K, n)
    """
    n = design.dimension
    nu = design.smoothness
    al_lo, au_lo = alpha_min[:, :n], alpha_min[:, n:]
    upper = au_lo - _softplus(pieces.rho_u[1] + au_lo - pieces.beta_u[0], nu)
    lower = al_lo - _softplus(pieces.beta_l[1] - pieces.rho_l[0] + al_lo, nu)
    return pieces.rho_width + upper + lower


def enclose(design: TubeDesign, pieces: Pieces, alpha_min: np.ndarray, alpha_max: np.ndarray,
            t0: np.ndarray, t1: np.ndarray) -> Enclosure:
    """Bounds of ``gamma_L``, ``gamma_U`` and their rates (eq. (10)) on each interval.

    Parameters
    ----------
    design : TubeDesign
        The tube.
    pieces : Pieces
        From :func:`piece_ranges` on the same intervals.
    alpha_min, alpha_max : ndarray, shape (K, 2n)
        Range of ``alpha`` on each interval.
    t0, t1 : ndarray, shape (K,)
        Seconds.

    Returns
    -------
    Enclosure
        Bounds of ``gamma_L``, ``gamma_U`` (state units), of ``|gamma_dot|`` (state units/s)
        and the least width ``gamma_U - gamma_L`` on each interval.
    """
    n = design.dimension
    nu = design.smoothness

    def smax(a, b):
        return reference.smooth_max_pair(a, b, nu)

    def smin(a, b):
        return -smax(-a, -b)

    al_lo, al_hi = alpha_min[:, :n], alpha_max[:, :n]
    au_lo, au_hi = alpha_min[:, n:], alpha_max[:, n:]
    lower_min = smax(pieces.rho_l[0] - al_hi, pieces.beta_l[0])
    lower_max = smax(pieces.rho_l[1] - al_lo, pieces.beta_l[1])
    upper_min = smin(pieces.rho_u[0] + au_lo, pieces.beta_u[0])
    upper_max = smin(pieces.rho_u[1] + au_hi, pieces.beta_u[1])
    # alpha_dot = theta(psi) / (psi + alpha)^2 - kappa alpha decreases in alpha and psi
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        z_lo = pieces.psi_lo + alpha_min
        fast = np.where(z_lo > 0, reference.trigger(design, pieces.psi_lo) / (z_lo * z_lo), np.inf)
        slow = reference.trigger(design, pieces.psi_hi) / (pieces.psi_hi + alpha_max) ** 2
    adot_max = fast - design.kappa * alpha_min
    adot_min = slow - design.kappa * alpha_max
    # gamma_dot is a convex combination of (rho_dot -+ alpha_dot) and beta_dot (eq. (10))
    (rl_min, rl_max), (ru_min, ru_max) = pieces.rho_rate
    (bl_min, bl_max), (bu_min, bu_max) = pieces.beta_rate
    gl_min = np.minimum(rl_min - adot_max[:, :n], bl_min)
    gl_max = np.maximum(rl_max - adot_min[:, :n], bl_max)
    gu_min = np.minimum(ru_min + adot_min[:, n:], bu_min)
    gu_max = np.maximum(ru_max + adot_max[:, n:], bu_max)
    rate_l = np.maximum(np.abs(gl_min), np.abs(gl_max))
    rate_u = np.maximum(np.abs(gu_min), np.abs(gu_max))
    width = np.maximum(upper_min - lower_max, width_lower_bound(design, pieces, alpha_min))
    # a bound moves in one period at most |gamma_dot| dt, and at most its whole range on
    # the interval (which is at least one period long)
    move = np.minimum(np.maximum(rate_l, rate_u) / design.rate_hz,
                      np.maximum(lower_max - lower_min, upper_max - upper_min))
    with np.errstate(divide="ignore", invalid="ignore"):
        # where the enclosure is empty the ratio means nothing: non-empty fails there
        ratio = np.where(width > 0, move / width, 0.0)
    ratio = np.where(np.isnan(ratio), np.inf, ratio)
    return Enclosure(t0, t1, lower_min, lower_max, upper_min, upper_max, alpha_min, alpha_max,
                     ratio.max(axis=1), pieces.psi_lo, pieces.psi_hi, width)


def enclose_tube(design: TubeDesign, samples) -> Enclosure:
    """Enclosures of ``gamma_L``, ``gamma_U`` on every sampling interval of ``samples``.

    ``alpha`` is the deployed sequence of ``samples`` (:func:`~.samples.sample_tube`),
    linearly interpolated, so on ``[t_k, t_{k+1}]`` it lies between ``alpha_k`` and
    ``alpha_{k+1}``; the other pieces are enclosed as in :func:`certify_tube`. Per sample:
    for checks that follow the sampled loop step by step (``verify``'s sampled check).
    The last :data:`KEPT_ENCLOSURES` are kept, per design, samples object and kind of
    kernels (:func:`~stt_codegen.tube.reference.numpy_math`); their arrays are read-only.

    Parameters
    ----------
    design : TubeDesign
    samples : TubeSamples
        ``t`` (N,) and ``alpha`` (N, 2n).

    Returns
    -------
    Enclosure
        ``N - 1`` intervals.
    """
    key = (design, id(samples), reference.numpy_math_active())
    found = _ENCLOSED.get(key)
    if found is not None and found[0] is samples:
        _ENCLOSED.move_to_end(key)
        return found[1]
    t0, t1 = samples.t[:-1], samples.t[1:]
    a0, a1 = samples.alpha[:-1], samples.alpha[1:]
    enclosure = enclose(design, piece_ranges(design, t0, t1), np.minimum(a0, a1),
                        np.maximum(a0, a1), t0, t1)
    for value in vars(enclosure).values():
        if isinstance(value, np.ndarray):
            value.setflags(write=False)
    _ENCLOSED[key] = (samples, enclosure)
    while len(_ENCLOSED) > KEPT_ENCLOSURES:
        _ENCLOSED.popitem(last=False)
    return enclosure


#: The enclosures :func:`enclose_tube` keeps (the latest last), each with the samples it
#: was computed for: a design's sampled check, the check with the balls after the per-axis
#: argument and its input proof's widths ask for the same one.
_ENCLOSED: OrderedDict = OrderedDict()
#: How many enclosures a process keeps.
KEPT_ENCLOSURES = 8





def enclose_later(design: TubeDesign, samples, begin: float, end: float) -> Enclosure:
    """Enclosures of ``gamma_L``, ``gamma_U`` on ``[t_k + begin, t_{k+1} + end]`` for every
    sampling interval ``k`` of ``samples``, ``0 <= begin <= end <= t_{k+1} - t_k``: e.g.
    the interval a command computed at ``t_k`` acts on after a computation delay
    (``begin = end = delay``).

    ``alpha`` is the deployed sequence, linearly interpolated as in :func:`enclose_tube`:
    such an interval lies within ``[t_k, t_{k+2}]``, so ``alpha`` on it lies between the
    least and the largest of ``alpha_k``, ``alpha_{k+1}``, ``alpha_{k+2}`` (the last
    interval takes ``alpha`` constant after the last sample).

    Parameters
    ----------
    design : TubeDesign
    samples : TubeSamples
        ``t`` (N,) and ``alpha`` (N, 2n).
    begin, end : float
        Seconds.

    Returns
    -------
    Enclosure
        ``N - 1`` intervals.
    """
    t0, t1 = samples.t[:-1] + begin, samples.t[1:] + end
    a0, a1 = samples.alpha[:-1], samples.alpha[1:]
    a2 = np.concatenate([samples.alpha[2:], samples.alpha[-1:]])
    return enclose(design, piece_ranges(design, t0, t1), np.minimum(np.minimum(a0, a1), a2),
                   np.maximum(np.maximum(a0, a1), a2), t0, t1)
