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

import numpy as np

from ...tube import reference
from ...tube.parameters import TubeDesign

#: Intervals of at most this many steps follow the extreme implicit steps one by one.
EXACT_STEPS = 4
#: Relative width at which :func:`step_root` stops refining its (rigorous) bracket.
STEP_ROOT_TOLERANCE = 1e-13


def alpha_fixed_point(psi: np.ndarray, theta: np.ndarray, kappa: float) -> tuple[np.ndarray,
                                                                                  np.ndarray]:
    """Bracket ``[lo, hi]`` of ``a*``, the root of ``kappa a = theta / (psi + a)^2`` with ``psi + a > 0``.

    ``f(a) = theta / (psi + a)^2 - kappa a`` is decreasing and convex on ``a > -psi``, with
    slope ``<= -kappa``. Newton starts at ``theta / (kappa psi^2)`` (``psi > 0``; right of
    the root, so the first step lands left of it) or just right of the pole (``f >= 0``),
    and from the left rises monotonically to the root. Every iterate ``x`` bounds the root:
    from below where ``f(x) >= 0``, from above otherwise, and then its Newton point bounds
    it from below (convexity); a probe right of a left iterate (twice its Newton step and
    a few ulps) bounds it from above where ``f <= 0`` there. Where a Newton step would
    leave the bracket (or ``x`` rounds onto the pole) the next point is the bracket's
    middle. Iterates until the bracket is ``1e-11`` relative (or ``1e-16`` absolute)
    wide; both ends are widened by ``1e-13`` relative for rounding.

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
    with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
        # right of the pole, f >= 0 at pole + eps: theta/eps^2 >= kappa (eps + max(-psi, 0))
        eps = np.minimum(np.cbrt(theta / (2.0 * kappa)),
                         np.sqrt(theta / (2.0 * kappa * np.maximum(-psi, 1e-300))))
        lo, hi = pole, pole + np.cbrt(theta / kappa)
        # psi > 0: theta / (kappa psi^2), right of the root and close to it when a* << psi
        x = np.where(psi > 0.0, np.minimum(theta / (kappa * psi * psi), hi), pole + eps)
        for _ in range(100):
            z = psi + x
            f = theta / (z * z) - kappa * x
            newton = x - f / (-2.0 * theta / (z * z * z) - kappa)
            usable = (z > 0.0) & np.isfinite(newton)        # else: x rounds onto the pole
            left = f >= 0.0                                  # x left of the root
            # right of a left iterate by twice its Newton step and a few ulps: an upper
            # bound wherever f <= 0 there
            probe = x + 2.0 * (newton - x) + 4.0 * np.spacing(x)
            z_probe = psi + probe
            above = (z_probe > 0.0) & (theta / (z_probe * z_probe) - kappa * probe <= 0.0)
            lo = np.where(usable, np.maximum(lo, np.where(left, x, newton)), lo)
            hi = np.where(usable, np.minimum(hi, np.where(left, np.where(above, probe, hi), x)),
                          hi)
            if np.all(hi - lo <= 1e-11 * hi + 1e-16):
                break
            # Newton, or bisection where Newton is not usable or leaves the bracket
            inside = usable & (newton >= lo) & (newton <= hi)
            x = np.where(inside, newton, 0.5 * (lo + hi))
    done = theta > 0.0
    return (np.where(done, np.maximum(pole, lo * (1.0 - 1e-13)), 0.0),
            np.where(done, hi * (1.0 + 1e-13) + 1e-300, 0.0))


def alpha_ranges(design: TubeDesign, psi_lo: np.ndarray, psi_hi: np.ndarray,
                  steps: np.ndarray, start: tuple[list, list]):
    """Ranges of the deployed ``alpha`` on each interval, carried from bounds at the first.

    On an interval of ``N`` steps with ``psi`` in ``[psi_lo, psi_hi]``, the deployed
    sequence lies between the constant-coefficient sequences of (``psi_hi``,
    ``theta_lo``) and (``psi_lo``, ``theta_hi``) from the bounds ``A`` at its start; each
    moves monotonically to its fixed point ``a*``. With ``f(a) = theta/(psi+a)^2 - kappa a``
    (decreasing): a sequence moving towards ``a*`` is never behind one implicit step of
    length ``N dt`` from ``A``, nor behind ``a* -+ |A - a*| q^N`` with
    ``q = 1 / (c + 2 dt theta / z^3)`` (convexity of ``1/z^2``); one moving away from
    ``A`` is never ahead of ``A + N dt f(A)``, nor past ``a*``. ``alpha >= 0`` always.
    At most :data:`EXACT_STEPS` steps follow the extreme implicit steps one by one.

    Parameters
    ----------
    psi_lo, psi_hi : ndarray, shape (K, 2n)
    steps : ndarray, shape (K,)
        Steps per interval (``inf`` for the tail).
    start : (list, list)
        Lower and upper bounds of ``alpha`` at the first interval's start.

    Returns
    -------
    rows_lo, rows_hi : list of list of float, (K, 2n)
        Range of ``alpha`` on each interval.
    entries : list of (list, list)
        Bounds of ``alpha`` at each interval's start (to resume from).
    """
    kappa, dt = design.kappa, 1.0 / design.rate_hz
    c = 1.0 + kappa * dt
    theta_hi = reference.trigger(design, psi_lo)
    theta_lo = reference.trigger(design, psi_hi)
    star_hi = alpha_fixed_point(psi_lo, theta_hi, kappa)[1]
    star_lo = alpha_fixed_point(psi_hi, theta_lo, kappa)[0]
    with np.errstate(divide="ignore", over="ignore", under="ignore", invalid="ignore"):
        q_lo = 1.0 / (c + 2.0 * dt * theta_lo / (psi_hi + star_lo) ** 3)
        decay_lo = np.where(np.isinf(steps)[:, None], 0.0,
                            np.power(q_lo, np.minimum(steps, 1e300)[:, None]))
    decay_lo = np.where(np.isnan(decay_lo), 1.0, decay_lo)   # no rate known: monotone only
    k_count, m = star_hi.shape
    a_lo, a_hi = list(start[0]), list(start[1])
    s_lo, s_hi = star_lo.tolist(), star_hi.tolist()
    d_lo, n_steps = decay_lo.tolist(), steps.tolist()
    out_lo, out_hi = [[0.0] * m for _ in range(k_count)], [[0.0] * m for _ in range(k_count)]
    p_lo, p_hi = psi_lo.tolist(), psi_hi.tolist()
    t_lo, t_hi = theta_lo.tolist(), theta_hi.tolist()
    two_dt = 2.0 * dt
    entries = []
    for k in range(k_count):
        entries.append((list(a_lo), list(a_hi)))
        sl, sh, row_lo, row_hi, steps_k = s_lo[k], s_hi[k], out_lo[k], out_hi[k], n_steps[k]
        if steps_k <= EXACT_STEPS:
            # few steps: follow the extreme backward-Euler sequences exactly
            for i in range(m):
                lo_i, hi_i = a_lo[i], a_hi[i]
                low, high = lo_i, hi_i
                for _ in range(int(steps_k)):
                    lo_i = max(step_root(lo_i, p_hi[k][i], t_lo[k][i], dt, c)[0], 0.0)
                    hi_i = step_root(hi_i, p_lo[k][i], t_hi[k][i], dt, c)[1]
                    low, high = min(low, lo_i), max(high, hi_i)
                row_lo[i], row_hi[i], a_lo[i], a_hi[i] = low, high, lo_i, hi_i
            continue
        if math.isinf(steps_k):
            # psi is constant from here on: alpha moves monotonically to a* for ever
            for i in range(m):
                row_lo[i] = min(a_lo[i], sl[i])
                row_hi[i] = max(a_hi[i], sh[i])
            continue
        span = steps_k * dt
        c_span = 1.0 + kappa * span
        for i in range(m):
            lo_i, hi_i = a_lo[i], a_hi[i]
            # lower sequence (psi_hi, theta_lo)
            if lo_i <= sl[i]:        # rising: one implicit step of N dt lags behind
                end = max(step_root(lo_i, p_hi[k][i], t_lo[k][i], span, c_span)[0],
                          sl[i] - (sl[i] - lo_i) * d_lo[k][i])
                row_lo[i] = lo_i
            else:                    # falling: no faster than its initial rate
                z = p_hi[k][i] + lo_i
                end = sl[i] if not z > 0.0 else max(
                    sl[i], lo_i + span * (t_lo[k][i] / (z * z) - kappa * lo_i))
                row_lo[i] = end
            a_lo[i] = end if end > 0.0 else 0.0
            # upper sequence (psi_lo, theta_hi)
            if hi_i >= sh[i]:        # falling: one implicit step of N dt lags behind
                q = 1.0 / (c + two_dt * t_hi[k][i] / (p_lo[k][i] + hi_i) ** 3)
                end = min(step_root(hi_i, p_lo[k][i], t_hi[k][i], span, c_span)[1],
                          sh[i] + (hi_i - sh[i]) * q ** steps_k)
                row_hi[i] = hi_i
            else:                    # rising: no faster than its initial rate
                z = p_lo[k][i] + hi_i
                end = sh[i] if not z > 0.0 else min(
                    sh[i], hi_i + span * (t_hi[k][i] / (z * z) - kappa * hi_i))
                row_hi[i] = end
            a_hi[i] = end
    return out_lo, out_hi, entries


def step_root(a: float, psi: float, theta: float, dt: float, c: float) -> tuple[float, float]:
    """Bracket of the backward-Euler root ``a+`` of ``g(x) = c x - a - dt theta / (psi + x)^2``.

    ``g`` has slope ``>= c`` on ``x > -psi``, so for any ``x`` there
    ``|a+ - x| <= |g(x)| / c``: the bracket is rigorous after any number of Newton
    iterations. They start at ``a`` (``alpha`` moves little per step) or, where
    ``psi + a <= 0``, at the left start of :func:`stt_codegen.tube.model.implicit_alpha_update`,
    and stop once the bracket is :data:`STEP_ROOT_TOLERANCE` relative wide.
    """
    big_a = dt * theta
    if not big_a > 0.0:
        return a / c, a / c
    x = a
    for _ in range(6):
        z = psi + x
        if not z > 0.0:
            break
        zz = z * z
        g = c * x - a - big_a / zz
        if abs(g) <= STEP_ROOT_TOLERANCE * c * x:
            return _root_bracket(x, g, c, a + big_a / zz)
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
