"""The coupled loop over one sampling interval: a Lyapunov level of law (13)'s own function.

In the coordinates of sample ``k`` (tube centre ``c``, half-widths ``h``), law (13) is
the gradient of ``W(x) = sum_i atanh(e_i)^2`` with ``e_i = (x_i - c_i) / h_i``:
``u_k = -2 k z_k``, ``z = grad W = (phi(e_i) / h_i)_i`` (the paper's ``V = |epsilon|^2 / 2``
up to the factor 8). For every ``g`` whose symmetric part has its eigenvalues in
``[g_min, g_max]`` the first-order change of ``W`` is ``-2 k z^T g z <= -2 k g_min |z|^2``:
the skew part and the coupling between axes drop out. The second-order term (the price of
holding ``u`` for ``dt``) is bounded with the curvature of ``W`` along the step. This
module bounds, for every ``e(t_k)`` with ``W <= r^2`` in a box, the level ``W`` reaches
during the interval (:func:`level_after`), and moves a level to the next sample's
coordinates (:func:`next_level`). docs/sampled-data.md, "The Lyapunov level", states and
proves every inequality. Plain floats, per block of ``g`` and interval.
"""

from __future__ import annotations

import itertools
import math
from typing import Sequence

from .operations import FLOATS

__all__ = ["psi", "others_box", "others_max", "level_after", "next_level"]

#: Bisection steps for the price of the budget in :func:`_concave_max` (any price gives a
#: valid bound; more steps only tighten it).
PRICE_HALVINGS = 16
#: Largest block for which :func:`others_max` enumerates the vertices of its budget
#: polytope (``2^m m`` of them); beyond, the box alone bounds it.
MAX_EXACT_BLOCK = 8


def psi(a: float, ops=FLOATS) -> float:
    """``phi(tanh a) = 2 a cosh(a)^2``: law (13)'s ``|u_i| gamma_d,i / (4 k)`` at
    ``atanh |e_i| = a``; odd, increasing, and ``psi(sqrt(b))^2`` is convex in ``b``.

    Parameters
    ----------
    a : float
        ``atanh |e_i|``.
    ops : optional
        :data:`~.operations.FLOATS` (default) or :data:`~.operations.SYMBOLS`.

    Returns
    -------
    float
        ``2 a cosh(a)^2``.
    """
    return 2.0 * a * ops.cosh(a) ** 2


def _terms(caps, halves, ops=FLOATS) -> list:
    """``(psi(sqrt(c_j)) / h_j)^2`` per axis."""
    return [(psi(ops.sqrt(c), ops) / h) ** 2 for c, h in zip(caps, halves)]


def others_box(limits: Sequence[float], halves: Sequence[float], ops=FLOATS) -> float:
    """:func:`others_max` without a ball (``level = inf``): the box's bound
    ``sum_j psi(a_j)^2 / h_j^2`` at ``a_j = limit_j``, in the same operations.

    Parameters
    ----------
    limits, halves : sequence of float
        As :func:`others_max`.
    ops : optional
        :data:`~.operations.FLOATS` (default) or :data:`~.operations.SYMBOLS`.

    Returns
    -------
    float
        1/state units squared.
    """
    return sum(_terms([a ** 2 for a in limits], halves, ops))


def others_max(limits: Sequence[float], level: float, halves: Sequence[float]) -> float:
    """``max sum_j psi(a_j)^2 / h_j^2`` over ``sum_j a_j^2 <= level^2``, ``|a_j| <= limit_j``.

    The square of the largest ``|z_J|`` (the gradient's part on the axes ``J``) over a
    ball of ``W`` cut by a box. In ``b_j = a_j^2`` the objective is convex and the set a
    polytope, so the maximum is at a vertex: every ``b_j`` at 0 or its limit, except at most
    one that takes what is left of the budget. Exact for up to :data:`MAX_EXACT_BLOCK` axes,
    the box's corner beyond (or when ``level`` is infinite).

    Parameters
    ----------
    limits : sequence of float
        ``max |atanh e_j|`` of the box, per axis of ``J``.
    level : float
        ``r``, the ball's radius in ``atanh`` units (``inf``: no ball).
    halves : sequence of float
        Half-widths ``h_j``, state units.

    Returns
    -------
    float
        The maximum (or, beyond :data:`MAX_EXACT_BLOCK` axes or without a ball, the box's
        bound), 1/state units squared.
    """
    caps = [min(a, level) ** 2 for a in limits]
    values = _terms(caps, halves)
    budget = level * level
    if not math.isfinite(budget) or sum(caps) <= budget or len(caps) > MAX_EXACT_BLOCK:
        return sum(values)
    best = 0.0
    m = len(caps)
    for full in itertools.product((False, True), repeat=m):
        used = sum(c for c, f in zip(caps, full) if f)
        if used > budget:
            continue
        total = sum(v for v, f in zip(values, full) if f)
        rest = budget - used
        extra = max((((psi(math.sqrt(min(c, rest))) / h) ** 2)
                     for c, h, f in zip(caps, halves, full) if not f), default=0.0)
        best = max(best, total + extra)
    return best


def level_after(level: float, limits: Sequence[float], halves: Sequence[float],
                curvature: Sequence[float], gain: float, dt: float, g_min: float,
                g_max: float, skew: float, push: float) -> float:
    """An upper bound of ``W(x(t_k + dt))`` for every ``e(t_k)`` with ``W <= level^2`` in the
    box, and every plant of the bounds; ``inf`` when the bound does not apply.

    With ``G`` the mean of ``g`` over the interval (it has the same bounds, which are
    convex) and ``d`` the mean of ``f + w``, ``x(t_k + dt) - x_k = dt (-2 k G z + d)``, and
    Taylor's formula with the curvature ``L_i >= phi'(e_i) / h_i^2`` along the step gives
    ``W(x) <= W + z^T Delta + sum_i L_i Delta_i^2 / 2``. Writing
    ``G = g_min I + P + K`` (``P`` symmetric, ``0 <= P <= g_max - g_min``, ``K`` skew,
    ``|K| <= skew``), the terms are bounded per axis (docs/sampled-data.md, eqs. (L1)-(L6)):

    ``W(x) <= sum_i [a_i^2 + omega_i z_i^2] + C``, ``z_i^2 >= 4 a_i^2 / h_i^2``,

    and the sum is maximized over the ball and the box (a linear program in ``a_i^2``).
    The Cauchy-Schwarz weights and the split of ``dt D |z|`` are free; each choice gives a
    valid bound, and the least of a few (one per axis taken as the direction of the
    maximum) is returned.

    Parameters
    ----------
    level : float
        ``r``: ``W(e(t_k)) <= r^2``.
    limits : sequence of float
        ``max |atanh e_i(t_k)|`` over the box, per axis of the block (``<= r`` is used).
    halves : sequence of float
        ``h_i``, state units.
    curvature : sequence of float
        ``L_i = phi'(rho_i) / h_i^2`` with ``rho_i >= |e_i|`` along the whole step.
    gain, dt : float
        ``k`` of law (13) and the sampling period, s.
    g_min, g_max, skew : float
        Bounds of ``g`` on the interval (eigenvalues of its symmetric part, norm of its
        skew part).
    push : float
        Bound of ``|f + w|``, state units per second.

    Returns
    -------
    float
        ``R^2`` with ``W(x(t_k + dt)) <= R^2``; ``inf`` if ``k dt L_max (g_max - g_min) >= 1``
        (the symmetric part's excess over ``g_min`` could overshoot; no bound).
    """
    m = len(halves)
    l_max, l_sum = max(curvature), sum(curvature)
    excess = gain * dt * l_max * (g_max - g_min)
    if excess >= 1.0:
        return math.inf
    amplify = 1.0 / (1.0 - excess)                              # mu, eq. (L4)
    caps = [min(a, level) ** 2 for a in limits]
    best = math.inf
    for j in range(m):               # the direction where the maximum is expected
        z_star = psi(min(max(limits[j], 1e-9), max(level, 1e-9))) / halves[j]
        terms = (2 * gain * g_min * math.sqrt(curvature[j]) * z_star,
                 2 * gain * skew * math.sqrt(max(l_sum - curvature[j], 0.0)) * z_star,
                 math.sqrt(l_max) * push)
        total = sum(terms)
        raw = [max(t / total, 1e-6) if total > 0 else 1.0 / 3 for t in terms]
        weights = [w / (sum(raw) * (1.0 + 1e-12)) for w in raw]   # Cauchy-Schwarz: sum <= 1
        theta = 1.0 / (2.0 * max(z_star, 1e-300))
        half_sq = 0.5 * dt * dt * amplify
        constant = half_sq * l_max * push ** 2 / weights[2]
        constant += dt * push / (4.0 * theta) if push > 0 else 0.0
        rates, extra = [], 0.0
        for i in range(m):
            omega = (-2 * gain * dt * g_min + (dt * push * theta if push > 0 else 0.0)
                     + half_sq * ((2 * gain * g_min) ** 2 * curvature[i] / weights[0]
                                  + (2 * gain * skew) ** 2 * (l_sum - curvature[i])
                                  / weights[1]))
            if omega < 0:
                rates.append(-4.0 * omega / halves[i] ** 2)
            else:
                rates.append(0.0)
                extra += omega * (psi(math.sqrt(caps[i])) / halves[i]) ** 2
        value = _concave_max(rates, caps, level * level)
        best = min(best, value + extra + constant)
    return best


def _gain_of(rate: float, cap: float, price: float) -> tuple[float, float]:
    """``(b, f(b) - price b)`` at the maximizer ``b`` on ``[0, cap]`` of
    ``f(b) = b (1 - rate) - 2 rate b^2 - (5/3) rate b^3`` minus ``price b`` (concave)."""
    slope0 = 1.0 - rate - price
    if slope0 <= 0.0:
        return 0.0, 0.0
    if rate == 0.0:
        b = cap
    else:
        # f'(b) - price = slope0 - 4 rate b - 5 rate b^2 = 0
        b = (-4.0 * rate + math.sqrt(16.0 * rate * rate + 20.0 * rate * slope0)) / (10.0 * rate)
        b = min(b, cap)
    return b, b * slope0 - 2.0 * rate * b * b - (5.0 / 3.0) * rate * b ** 3


def _concave_max(rates: Sequence[float], caps: Sequence[float], budget: float) -> float:
    """An upper bound of ``max sum_i f_i(b_i)`` over ``sum b_i <= budget``,
    ``0 <= b_i <= cap_i``, ``f_i`` as in :func:`_gain_of` (``rate_i >= 0``).

    ``f_i(b)`` bounds ``b - rate_i b cosh^4(sqrt b)`` from above (``cosh^4 x >= 1 + 2 x^2 +
    (5/3) x^4``: its Taylor coefficients are all positive). Lagrangian duality: for every
    price ``p >= 0`` the maximum is at most ``p budget + sum_i max_b (f_i(b) - p b)``, each
    term in closed form; the price is found by bisection (:data:`PRICE_HALVINGS`), and
    whatever price it ends on, the least value seen is a valid bound.
    """
    pairs = list(zip(rates, caps))

    def dual(price: float) -> tuple[float, float]:
        total, used = price * budget, 0.0
        for rate, cap in pairs:
            b, v = _gain_of(rate, cap, price)
            total += v
            used += b
        return total, used

    best, used = dual(0.0)
    if used <= budget:
        return best
    lo, hi = 0.0, max(1.0 - r for r in rates)
    for _ in range(PRICE_HALVINGS):
        mid = 0.5 * (lo + hi)
        value, used = dual(mid)
        best = min(best, value)
        if used > budget:
            lo = mid
        else:
            hi = mid
    return min(best, dual(hi)[0])


def next_level(level: float, alpha: Sequence[float], beta: Sequence[float],
               limits: Sequence[float] | None = None) -> float:
    """A radius of ``W`` in the next sample's coordinates that contains the set
    ``{sum a_i^2 <= level^2, |a_i| <= limit_i}`` of this sample's (``a_i = atanh e_i``).

    With ``e'_i = alpha_i e_i + beta_i`` (``alpha_i = h_i / h'_i``,
    ``beta_i = (c_i - c'_i) / h'_i``), ``m_i(a) = atanh(alpha_i tanh(a) + beta_i)``, and per
    axis ``|m_i(a_i)| <= |m_i(0)| + L_i |a_i|`` (mean value theorem) with
    ``L_i = sup |m_i'|`` on ``|a| <= min(level, limit_i)``; by Minkowski's inequality
    ``|m(a)| <= |m(0)| + |(L_i a_i)_i|``, and the largest ``sum L_i^2 a_i^2`` over the set is
    a linear program in ``a_i^2`` (filled greedily). ``m_i' = alpha_i (1 - t^2) / (1 -
    (alpha_i t + beta_i)^2)`` at ``t = tanh a``; its extremes are at the ends or at a root of
    ``alpha beta t^2 + (alpha^2 + beta^2 - 1) t + alpha beta``.

    Parameters
    ----------
    level : float
        ``r``: this sample's set has ``sum a_i^2 <= r^2``.
    alpha, beta : sequence of float
        ``alpha_i = h_i / h'_i`` and ``beta_i = (c_i - c'_i) / h'_i`` per axis: the change of
        coordinates to the next sample's centre ``c'`` and half-widths ``h'``.
    limits : sequence of float, optional
        Bounds of ``|a_i|`` (default: ``level`` for every axis).

    Returns
    -------
    float
        ``inf`` when the set reaches ``|e'_i| >= 1``.
    """
    if limits is None:
        limits = [level] * len(alpha)
    shift, weighted = 0.0, []
    for al, be, lim in zip(alpha, beta, limits):
        if abs(be) >= 1.0:
            return math.inf
        shift += math.atanh(be) ** 2
        cap = min(level, lim)
        top = math.tanh(cap)
        points = [-top, top]
        qa, qb = al * be, al * al + be * be - 1.0
        if qa != 0.0:
            disc = qb * qb - 4.0 * qa * qa
            if disc >= 0.0:
                root = math.sqrt(disc)
                points += [t for t in ((-qb + root) / (2 * qa), (-qb - root) / (2 * qa))
                           if -top < t < top]
        slope = 0.0
        for t in points:
            inner = al * t + be
            if abs(inner) >= 1.0:
                return math.inf
            slope = max(slope, al * (1.0 - t * t) / (1.0 - inner * inner))
        weighted.append((slope * slope, cap * cap))
    budget, spread = level * level, 0.0
    for square, cap in sorted(weighted, reverse=True):
        take = min(cap, budget)
        spread += square * take
        budget -= take
        if budget <= 0.0:
            break
    return math.sqrt(shift) + math.sqrt(spread)
