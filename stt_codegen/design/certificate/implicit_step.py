"""Rigorous bounds of the deployed ``alpha``: the backward-Euler step of eq. (11).

The implicit step's root ``a+`` of ``c a - a_k - dt theta / (psi + a)^2``,
``c = 1 + kappa dt``, increases with ``a_k`` and ``theta`` and decreases with ``psi``. With
``psi >= psi_lo`` and ``theta <= theta_hi`` on an interval the deployed sequence stays
below the constant-coefficient one, which moves monotonically to its fixed point ``a*``
(``kappa a = theta / (psi + a)^2``, :func:`alpha_fixed_point`) with
``a_N - a* <= (a_0 - a*) c^-N``; lower bounds alike (:func:`alpha_ranges`). The deployed
Newton iterate lies at or below the root (:func:`step_root` brackets it), so every upper
bound on ``alpha`` (what could widen the tube into an obstacle) holds for it exactly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...tube import reference
from ...tube.parameters import TubeDesign

__all__ = ["EXACT_STEPS", "FIXED_POINT_NEWTON_STEPS", "Propagation", "STEP_ROOT_TOLERANCE",
           "SequenceBounds", "alpha_fixed_point", "alpha_ranges", "sequence_bounds",
           "step_root"]

#: Intervals of at most this many steps follow the extreme implicit steps one by one.
EXACT_STEPS = 4
#: Plain Newton steps of :func:`alpha_fixed_point` from ``a = 0`` before its bracket is
#: checked (enough for every element of the bench's arenas; slower ones are searched).
FIXED_POINT_NEWTON_STEPS = 6
#: Relative width at which :func:`step_root` stops refining its (rigorous) bracket.
STEP_ROOT_TOLERANCE = 1e-13


def alpha_fixed_point(psi: np.ndarray, theta: np.ndarray, kappa: float) -> tuple[np.ndarray,
                                                                                  np.ndarray]:
    """Bracket ``[lo, hi]`` of ``a*``, the root of ``kappa a = theta / (psi + a)^2`` with ``psi + a > 0``.

    ``f(a) = theta / (psi + a)^2 - kappa a`` is decreasing and convex on ``a > -psi``, with
    slope ``<= -kappa``. Every point ``x`` bounds the root: from below where ``f(x) >= 0``,
    from above otherwise, and then its Newton point bounds it from below (convexity); a
    probe right of a left point (twice its Newton step and a few ulps) bounds it from above
    where ``f <= 0`` there.

    :data:`FIXED_POINT_NEWTON_STEPS` plain Newton steps, each element by itself, start left
    of the root and from there rise monotonically to it (convexity): for ``psi > 0`` at the
    largest of ``0``, ``(theta / kappa)^(1/3) - psi`` (``kappa a (psi + a)^2 < kappa (psi +
    a)^3 <= theta``) and ``min(psi, theta / (4 kappa psi^2))`` (``(psi + a)^2 <= 4 psi^2``),
    else just right of the pole (``f >= 0`` at ``pole + eps``, below). The last point's
    bracket is kept where it is ``1e-11`` relative (or ``1e-16`` absolute) wide. The other
    elements (none on the bench's arenas) take the bracketed search: Newton from
    ``theta / (kappa psi^2)`` (``psi > 0``; right of the root, so the first step lands left
    of it) or from ``pole + eps``, bisection where a Newton step would leave the bracket (or
    ``x`` rounds onto the pole), until the bracket is as narrow. Both ends are widened by
    ``1e-13`` relative for rounding.

    Parameters
    ----------
    psi, theta : ndarray, same shape
        State units and ``1/s`` state units^3 (eq. (11)); ``theta >= 0``.
    kappa : float
        ``1/s``.

    Returns
    -------
    lo, hi : ndarray, the shape of ``psi``
        ``0`` where ``theta = 0``.
    """
    pole = np.maximum(0.0, -psi)
    if not pole.size:
        return pole, pole.copy()
    with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
        x = np.where(psi > 0.0,
                     np.maximum(np.maximum(0.0, np.cbrt(theta / kappa) - psi),
                                np.minimum(psi, theta / (4.0 * kappa * psi * psi))),
                     pole + _pole_offset(psi, theta, kappa))
        minus_two_theta = -2.0 * theta  # f' = -2 theta / z^3 - kappa
        for _ in range(FIXED_POINT_NEWTON_STEPS):
            z = psi + x
            zz = z * z
            x = x - (theta / zz - kappa * x) / (minus_two_theta / (zz * z) - kappa)
        z = psi + x
        zz = z * z
        f = theta / zz - kappa * x
        newton = x - f / (minus_two_theta / (zz * z) - kappa)
        left = f >= 0.0
        probe = x + 2.0 * (newton - x) + 4.0 * np.spacing(x)
        z_probe = psi + probe
        above = (z_probe > 0.0) & (theta / (z_probe * z_probe) - kappa * probe <= 0.0)
        lo, hi = np.where(left, x, newton), np.where(left, probe, x)
        # kept: x off the pole, a finite Newton point, an upper bound found right of a left
        # point, and narrow
        kept = (z > 0.0) & np.isfinite(newton) & (above | ~left) & (hi - lo <= 1e-11 * hi + 1e-16)
    if not kept.all():
        rest = ~kept
        lo[rest], hi[rest] = _bracketed_search(psi[rest], theta[rest], kappa, pole[rest])
    done = theta > 0.0
    return (np.where(done, np.maximum(pole, lo * (1.0 - 1e-13)), 0.0),
            np.where(done, hi * (1.0 + 1e-13) + 1e-300, 0.0))


def _pole_offset(psi: np.ndarray, theta: np.ndarray, kappa: float) -> np.ndarray:
    """``eps`` with ``f >= 0`` at ``max(0, -psi) + eps``, right of the pole:
    ``theta / eps^2 >= kappa (eps + max(-psi, 0))``."""
    return np.minimum(np.cbrt(theta / (2.0 * kappa)),
                      np.sqrt(theta / (2.0 * kappa * np.maximum(-psi, 1e-300))))


def _bracketed_search(psi: np.ndarray, theta: np.ndarray, kappa: float,
                      pole: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The bracketed search of :func:`alpha_fixed_point` (``pole = max(0, -psi)``): the
    bracket before its widening for rounding."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
        lo, hi = pole.copy(), pole + np.cbrt(theta / kappa)
        # psi > 0: theta / (kappa psi^2), right of the root and close to it when a* << psi
        x = np.where(psi > 0.0, np.minimum(theta / (kappa * psi * psi), hi),
                     pole + _pole_offset(psi, theta, kappa))
        minus_two_theta = -2.0 * theta  # f' = -2 theta / z^3 - kappa
        for _ in range(100):
            z = psi + x
            zz = z * z
            f = theta / zz - kappa * x
            newton = x - f / (minus_two_theta / (zz * z) - kappa)
            usable = (z > 0.0) & np.isfinite(newton)        # else: x rounds onto the pole
            left = f >= 0.0                                  # x left of the root
            # right of a left iterate by twice its Newton step and a few ulps: an upper
            # bound wherever f <= 0 there
            probe = x + 2.0 * (newton - x) + 4.0 * np.spacing(x)
            z_probe = psi + probe
            above = (z_probe > 0.0) & (theta / (z_probe * z_probe) - kappa * probe <= 0.0)
            # the bracket moves only where the iterate is usable (in place)
            new_hi = np.where(left, np.where(above, probe, hi), x)
            np.maximum(lo, np.where(left, x, newton), out=lo, where=usable)
            np.minimum(hi, new_hi, out=hi, where=usable)
            if (hi - lo <= 1e-11 * hi + 1e-16).all():
                break
            # Newton, or bisection where Newton is not usable or leaves the bracket
            inside = usable & (newton >= lo) & (newton <= hi)
            x = np.where(inside, newton, 0.5 * (lo + hi))
    return lo, hi


def _fixed_points(psi_lo: np.ndarray, psi_hi: np.ndarray, theta_lo: np.ndarray,
                  theta_hi: np.ndarray, kappa: float) -> tuple[np.ndarray, np.ndarray]:
    """The lower end of ``a*``'s bracket for (``psi_hi``, ``theta_lo``) and the upper end for
    (``psi_lo``, ``theta_hi``), in one vectorized :func:`alpha_fixed_point` (its cost is
    mostly per iteration, not per element)."""
    lo, hi = alpha_fixed_point(np.concatenate([psi_hi, psi_lo]),
                               np.concatenate([theta_lo, theta_hi]), kappa)
    half = psi_lo.shape[0]
    return lo[:half], hi[half:]


class Propagation:
    """The per-interval coefficients of :func:`alpha_ranges`, to carry bounds one interval on.

    Built once for a partition (vectorized: ``theta``, the fixed points ``a*`` of the longer
    intervals, their decay factors); :meth:`advance` then carries the bounds of ``alpha``
    across interval ``k`` (a plain-Python loop over the ``2n`` components).

    Parameters
    ----------
    design : TubeDesign
    psi_lo, psi_hi : ndarray, shape (K, 2n)
    steps : ndarray, shape (K,)
        Steps per interval (``inf`` for the tail).
    step_psi : list, optional
        As in :func:`alpha_ranges`.
    """

    def __init__(self, design: TubeDesign, psi_lo: np.ndarray, psi_hi: np.ndarray,
                 steps: np.ndarray, step_psi: list | None = None):
        kappa, dt = design.kappa, 1.0 / design.rate_hz
        c = 1.0 + kappa * dt
        theta_hi = reference.trigger(design, psi_lo)
        theta_lo = reference.trigger(design, psi_hi)
        # the fixed points matter on the longer intervals only (the short ones follow
        # their steps)
        star_hi, star_lo = np.zeros_like(psi_lo), np.zeros_like(psi_hi)
        long = steps > EXACT_STEPS
        if long.any():
            star_lo[long], star_hi[long] = _fixed_points(psi_lo[long], psi_hi[long],
                                                         theta_lo[long], theta_hi[long], kappa)
        with np.errstate(divide="ignore", over="ignore", under="ignore", invalid="ignore"):
            q_lo = 1.0 / (c + 2.0 * dt * theta_lo / (psi_hi + star_lo) ** 3)
            decay_lo = np.where(np.isinf(steps)[:, None], 0.0,
                                np.power(q_lo, np.minimum(steps, 1e300)[:, None]))
        decay_lo = np.where(np.isnan(decay_lo), 1.0, decay_lo)  # no rate known: monotone only
        self.kappa, self.dt, self.c = kappa, dt, c
        self.m = psi_lo.shape[1]
        self.steps = steps.tolist()
        # per interval, per component: (psi_lo, psi_hi, theta_lo, theta_hi, a*_lo, a*_hi,
        # decay_lo); an interval's rows are converted to floats when it is first carried
        # (advance reads them one by one; a re-propagation carries a few of the intervals)
        self._table = np.stack([psi_lo, psi_hi, theta_lo, theta_hi, star_lo, star_hi,
                                decay_lo], axis=-1)
        self._rows: dict[int, list] = {}
        self.step_psi = step_psi

    def row(self, k: int) -> list:
        """Interval ``k``'s coefficients, per component ``(psi_lo, psi_hi, theta_lo,
        theta_hi, a*_lo, a*_hi, decay_lo)``, as floats."""
        row = self._rows.get(k)
        if row is None:
            row = self._rows[k] = self._table[k].tolist()
        return row

    def advance(self, k: int, a_lo: list, a_hi: list) -> tuple[list, list]:
        """Carry the bounds ``a_lo``, ``a_hi`` of ``alpha`` at interval ``k``'s start to its end.

        Parameters
        ----------
        k : int
        a_lo, a_hi : list of float, (2n,)
            Bounds at the start; overwritten with the bounds at the end (unchanged for the
            tail, which has none).

        Returns
        -------
        row_lo, row_hi : list of float, (2n,)
            Range of ``alpha`` on the interval.
        """
        kappa, dt, c = self.kappa, self.dt, self.c
        steps_k, row = self.steps[k], self.row(k)
        if steps_k <= EXACT_STEPS:
            return self._follow(k, int(steps_k), a_lo, a_hi)
        row_lo, row_hi = [0.0] * self.m, [0.0] * self.m
        if math.isinf(steps_k):
            # psi is constant from here on: alpha moves monotonically to a* for ever
            for i, (_, _, _, _, sl, sh, _) in enumerate(row):
                row_lo[i] = min(a_lo[i], sl)
                row_hi[i] = max(a_hi[i], sh)
            return row_lo, row_hi
        span = steps_k * dt
        c_span = 1.0 + kappa * span
        for i, (pl, ph, tl, th, sl, sh, d_lo) in enumerate(row):
            lo_i, hi_i = a_lo[i], a_hi[i]
            # lower sequence (psi_hi, theta_lo)
            if lo_i <= sl:           # rising: one implicit step of N dt lags behind
                end = max(step_root(lo_i, ph, tl, span, c_span)[0], sl - (sl - lo_i) * d_lo)
                row_lo[i] = lo_i
            else:                    # falling: no faster than its initial rate
                z = ph + lo_i
                end = sl if not z > 0.0 else max(sl, lo_i + span * (tl / (z * z) - kappa * lo_i))
                row_lo[i] = end
            a_lo[i] = end if end > 0.0 else 0.0
            # upper sequence (psi_lo, theta_hi)
            if hi_i >= sh:           # falling: one implicit step of N dt lags behind
                q = 1.0 / (c + 2.0 * dt * th / (pl + hi_i) ** 3)
                end = min(step_root(hi_i, pl, th, span, c_span)[1],
                          sh + (hi_i - sh) * q ** steps_k)
                row_hi[i] = hi_i
            else:                    # rising: no faster than its initial rate
                z = pl + hi_i
                end = sh if not z > 0.0 else min(sh, hi_i + span * (th / (z * z) - kappa * hi_i))
                row_hi[i] = end
            a_hi[i] = end
        return row_lo, row_hi

    def _follow(self, k: int, count: int, a_lo: list, a_hi: list) -> tuple[list, list]:
        """:meth:`advance` on an interval of ``count <= EXACT_STEPS`` steps: the extreme
        backward-Euler sequences step by step, each step with its own ``psi`` where it is
        known, else the interval's range."""
        dt, c = self.dt, self.c
        own = None if self.step_psi is None else self.step_psi[k]
        row_lo, row_hi = [0.0] * self.m, [0.0] * self.m
        for i, (pl, ph, tl, th, _, _, _) in enumerate(self.row(k)):
            lo_i, hi_i = a_lo[i], a_hi[i]
            low, high = lo_i, hi_i
            if own is None:          # the interval's range of psi
                for _ in range(count):
                    lo_i = max(step_root(lo_i, ph, tl, dt, c)[0], 0.0)
                    hi_i = step_root(hi_i, pl, th, dt, c)[1]
                    low, high = min(low, lo_i), max(high, hi_i)
            else:                    # the step's own psi
                for own_pl, own_ph, own_tl, own_th in zip(own[0], own[1], own[2], own[3]):
                    lo_i = max(step_root(lo_i, own_ph[i], own_tl[i], dt, c)[0], 0.0)
                    hi_i = step_root(hi_i, own_pl[i], own_th[i], dt, c)[1]
                    low, high = min(low, lo_i), max(high, hi_i)
            row_lo[i], row_hi[i], a_lo[i], a_hi[i] = low, high, lo_i, hi_i
        return row_lo, row_hi


def alpha_ranges(design: TubeDesign, psi_lo: np.ndarray, psi_hi: np.ndarray,
                  steps: np.ndarray, start: tuple[list, list],
                  step_psi: list | None = None):
    """Ranges of the deployed ``alpha`` on each interval, carried from bounds at the first.

    On an interval of ``N`` steps with ``psi`` in ``[psi_lo, psi_hi]``, the deployed
    sequence lies between the constant-coefficient sequences of (``psi_hi``,
    ``theta_lo``) and (``psi_lo``, ``theta_hi``) from the bounds ``A`` at its start; each
    moves monotonically to its fixed point ``a*``. With ``f(a) = theta/(psi+a)^2 - kappa a``
    (decreasing): a sequence moving towards ``a*`` is never behind one implicit step of
    length ``N dt`` from ``A``, nor behind ``a* -+ |A - a*| q^N`` with
    ``q = 1 / (c + 2 dt theta / z^3)`` (convexity of ``1/z^2``); one moving away from
    ``A`` is never ahead of ``A + N dt f(A)``, nor past ``a*``. ``alpha >= 0`` always.
    At most :data:`EXACT_STEPS` steps follow the extreme implicit steps one by one
    (:class:`Propagation`).

    Parameters
    ----------
    design : TubeDesign
        The tube (``theta0``, ``mu``, ``kappa``, ``rate_hz``).
    psi_lo, psi_hi : ndarray, shape (K, 2n)
    steps : ndarray, shape (K,)
        Steps per interval (``inf`` for the tail).
    start : (list, list)
        Lower and upper bounds of ``alpha`` at the first interval's start.
    step_psi : list, optional
        Per interval: for one of at most :data:`EXACT_STEPS` steps, the ranges
        ``(psi_lo, psi_hi, theta_lo, theta_hi)`` of ``psi`` and ``theta`` at the instants
        its steps use, nested lists (steps, 2n) (the deployed step ``k -> k + 1`` takes
        ``psi(t_{k+1})``), so each step is followed with its own ``psi`` instead of the
        interval's range; ``None`` (or no list): the interval's range.

    Returns
    -------
    rows_lo, rows_hi : list of list of float, (K, 2n)
        Range of ``alpha`` on each interval.
    entries : list of (list, list)
        Bounds of ``alpha`` at each interval's start (to resume from).
    """
    run = Propagation(design, psi_lo, psi_hi, steps, step_psi)
    a_lo, a_hi = list(start[0]), list(start[1])
    out_lo, out_hi, entries = [], [], []
    for k in range(len(run.steps)):
        entries.append((list(a_lo), list(a_hi)))
        row_lo, row_hi = run.advance(k, a_lo, a_hi)
        out_lo.append(row_lo)
        out_hi.append(row_hi)
    return out_lo, out_hi, entries


@dataclass(frozen=True)
class SequenceBounds:
    """The extreme constant-coefficient sequences of intervals, to bound ``alpha`` inside them.

    On an interval with ``psi`` in ``[psi_lo, psi_hi]`` and ``alpha`` in ``[A_lo, A_hi]`` at
    its start, the deployed ``alpha`` after ``j`` steps lies between the sequences of
    (``psi_hi``, ``theta_lo``) from ``A_lo`` and of (``psi_lo``, ``theta_hi``) from ``A_hi``
    (:func:`alpha_ranges`), for every ``j``, not only at the interval's end: :meth:`within`
    bounds it over a part of the interval, with the bounds :func:`alpha_ranges` uses for the
    whole. Arrays (K, 2n); build with :func:`sequence_bounds`.

    Attributes
    ----------
    start_lo, start_hi : ndarray, shape (K, 2n)
        Bounds ``A_lo``, ``A_hi`` of ``alpha`` at each interval's start, state units.
    star_lo, star_hi : ndarray, shape (K, 2n)
        Fixed points ``a*`` of the lower and the upper sequence.
    q_lo, q_hi : ndarray, shape (K, 2n)
        Contraction factors ``q`` of the two sequences towards ``a*`` (1: none known).
    rate_lo, rate_hi : ndarray, shape (K, 2n)
        ``f(A) = theta / (psi + A)^2 - kappa A`` at the two starts, state units/s (``-+inf``
        where ``psi + A <= 0``).
    dt : float
        Sampling period, s.
    """

    start_lo: np.ndarray
    start_hi: np.ndarray
    star_lo: np.ndarray
    star_hi: np.ndarray
    q_lo: np.ndarray
    q_hi: np.ndarray
    rate_lo: np.ndarray
    rate_hi: np.ndarray
    dt: float

    def within(self, rows: np.ndarray, j0: np.ndarray, j1: np.ndarray) -> tuple[np.ndarray,
                                                                               np.ndarray]:
        """Range of the deployed ``alpha`` over steps ``j0 .. j1`` of intervals ``rows``.

        The lower sequence rising to ``a*`` is at least ``a* - (a* - A) q^j`` (least at
        ``j0``); falling, at least ``max(a*, A + j dt f(A))`` (least at ``j1``). The upper
        sequence alike, mirrored. ``alpha >= 0``.

        Parameters
        ----------
        rows : ndarray of int, shape (P,)
            Interval of each part.
        j0, j1 : ndarray, shape (P,)
            Steps from the interval's start, ``0 <= j0 <= j1``.

        Returns
        -------
        lo, hi : ndarray, shape (P, 2n)
        """
        a_lo, a_hi = self.start_lo[rows], self.start_hi[rows]
        s_lo, s_hi = self.star_lo[rows], self.star_hi[rows]
        j0, j1 = j0[:, None], j1[:, None]
        with np.errstate(over="ignore", under="ignore", invalid="ignore"):
            rise = s_lo - (s_lo - a_lo) * np.power(self.q_lo[rows], j0)
            fall = np.maximum(s_lo, a_lo + j1 * self.dt * self.rate_lo[rows])
            lo = np.where(a_lo <= s_lo, np.maximum(a_lo, _nan_to(rise, -np.inf)),
                          _nan_to(fall, -np.inf))
            drop = s_hi + (a_hi - s_hi) * np.power(self.q_hi[rows], j0)
            climb = np.minimum(s_hi, a_hi + j1 * self.dt * self.rate_hi[rows])
            hi = np.where(a_hi >= s_hi, _nan_to(drop, np.inf), _nan_to(climb, np.inf))
        return np.maximum(lo, 0.0), hi


#: The largest finite float: :func:`numpy.nan_to_num` maps ``-+inf`` to ``-+`` it.
_LARGEST = float(np.finfo(float).max)


def _nan_to(values: np.ndarray, nan: float) -> np.ndarray:
    """``numpy.nan_to_num(values, nan=nan)`` in four ufunc calls (its Python wrapper costs
    more than they do on small arrays): NaN to ``nan``, ``-+inf`` to the largest finite
    floats."""
    return np.where(np.isnan(values), nan, np.minimum(np.maximum(values, -_LARGEST), _LARGEST))


def sequence_bounds(design: TubeDesign, psi_lo: np.ndarray, psi_hi: np.ndarray,
                    start_lo: np.ndarray, start_hi: np.ndarray) -> SequenceBounds:
    """:class:`SequenceBounds` of intervals with ``psi`` in ``[psi_lo, psi_hi]`` (K, 2n) and
    ``alpha`` in ``[start_lo, start_hi]`` at their start (K, 2n).

    Parameters
    ----------
    design : TubeDesign
        The tube (``theta0``, ``mu``, ``kappa``, ``rate_hz``).
    psi_lo, psi_hi : ndarray, shape (K, 2n)
        Range of ``psi`` (eq. (11)) on each interval, state units.
    start_lo, start_hi : ndarray, shape (K, 2n)
        Range of ``alpha`` at each interval's start, state units.

    Returns
    -------
    SequenceBounds
        The two extreme sequences of every interval.
    """
    kappa, dt = design.kappa, 1.0 / design.rate_hz
    c = 1.0 + kappa * dt
    theta_hi = reference.trigger(design, psi_lo)
    theta_lo = reference.trigger(design, psi_hi)
    star_lo, star_hi = _fixed_points(psi_lo, psi_hi, theta_lo, theta_hi, kappa)
    with np.errstate(divide="ignore", over="ignore", under="ignore", invalid="ignore"):
        q_lo = 1.0 / (c + 2.0 * dt * theta_lo / (psi_hi + star_lo) ** 3)
        q_lo = np.where(np.isnan(q_lo), 1.0, q_lo)        # no rate known: monotone only
        q_hi = 1.0 / (c + 2.0 * dt * theta_hi / (psi_lo + start_hi) ** 3)
        z_lo, z_hi = psi_hi + start_lo, psi_lo + start_hi
        # f(A) = theta / (psi + A)^2 - kappa A; where psi + A <= 0 only a* bounds the move
        rate_lo = np.where(z_lo > 0.0, theta_lo / (z_lo * z_lo) - kappa * start_lo, -np.inf)
        rate_hi = np.where(z_hi > 0.0, theta_hi / (z_hi * z_hi) - kappa * start_hi, np.inf)
    return SequenceBounds(start_lo, start_hi, star_lo, star_hi, q_lo, q_hi, rate_lo, rate_hi, dt)


def step_root(a: float, psi: float, theta: float, dt: float, c: float,
              _tolerance: float = STEP_ROOT_TOLERANCE) -> tuple[float, float]:
    """Bracket of the backward-Euler root ``a+`` of ``g(x) = c x - a - dt theta / (psi + x)^2``.

    ``g`` has slope ``>= c`` on ``x > -psi``, so for any ``x`` there
    ``|a+ - x| <= |g(x)| / c``: the bracket is rigorous after any number of Newton
    iterations. They start at ``a`` (``alpha`` moves little per step) or, where
    ``psi + a <= 0``, at the left start of :func:`stt_codegen.tube.model.implicit_alpha_update`,
    and stop once the bracket is :data:`STEP_ROOT_TOLERANCE` relative wide.

    Parameters
    ----------
    a : float
        ``alpha`` before the step, state units.
    psi : float
        ``psi`` at the end of the step, state units.
    theta : float
        ``theta`` at the end of the step.
    dt : float
        Step, s.
    c : float
        ``1 + kappa dt``.
    _tolerance : float, optional
        Relative width at which Newton stops (default :data:`STEP_ROOT_TOLERANCE`).

    Returns
    -------
    lo, hi : float
        ``lo <= a+ <= hi``.
    """
    big_a = dt * theta
    if not big_a > 0.0:
        return a / c, a / c
    x = a
    # the bracket's arithmetic is _root_bracket's, written out in this hot loop
    for _ in range(6):
        z = psi + x
        if not z > 0.0:
            break
        zz = z * z
        pull = big_a / zz
        g = c * x - a - pull
        if abs(g) <= _tolerance * c * x:
            slack = 1e-15 * (c * abs(x) + (a + pull)) / c
            if g > 0.0:
                return x - g / c - slack, x + slack
            return x - slack, x - g / c + slack
        x_next = x - g / (c + 2.0 * big_a / (zz * z))
        if x_next == x:
            break
        x = x_next
    if not psi + x > 0.0:
        # left start (g <= 0 there): Newton then rises monotonically inside the domain
        q = max(-c * psi - a, 1e-300)
        x = max(a / c, -psi + min((big_a / (2.0 * c)) ** (1.0 / 3.0),
                                  math.sqrt(big_a / (2.0 * q))))
        for _ in range(60):
            z = psi + x
            x_next = x - (c * x - a - big_a / (z * z)) / (c + 2.0 * big_a / (z * z * z))
            if not x_next > x:
                break
            x = x_next
    z = psi + x
    g = c * x - a - big_a / (z * z)
    return _root_bracket(x, g, c, a + big_a / (z * z))


def _root_bracket(x: float, g: float, c: float, terms: float) -> tuple[float, float]:
    """``[x, x - g/c]`` or ``[x - g/c, x]`` (slope ``>= c``), widened by the rounding of
    ``g = c x - terms`` (a few ulps of its largest term)."""
    slack = 1e-15 * (c * abs(x) + terms) / c
    lo, hi = (x - g / c, x) if g > 0.0 else (x, x - g / c)
    return lo - slack, hi + slack
