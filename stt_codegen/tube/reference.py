"""Numeric reference: eqs. (2)-(13) of the paper in numpy, the oracle for every backend.

Written directly from the paper's equations and independently of the CasADi model:
derivatives are written out by hand (not differentiated automatically), the smooth
max/min uses the paper's log-sum-exp form through ``numpy.logaddexp``, and the implicit
``alpha`` step is solved by bisection rather than Newton's method.

Shapes: ``t`` is ``(N,)``; ``x`` is ``(N, n)``; ``alpha`` is ``(N, 2n)`` and holds
``[alpha_L, alpha_U]``; scalars broadcast. Every function returns arrays with a leading
``N`` axis.
"""

from __future__ import annotations

import contextlib
import contextvars
import functools
import math
from collections.abc import Sequence

import numpy as np

from .parameters import (CRUISE, CRUISE_RAMP, E_MAX, GAMMA_D_MIN, GLIDE, GLIDE_RAMP, GLIDE_TURN,
                         LOWER, SCURVE, SCURVE_TURN,
                         SMOOTHSTEP, STATUS_INPUT_CLAMPED, STATUS_OK, STATUS_OUTSIDE_TUBE, TANH,
                         ReachSegment, TubeDesign, step_status)

__all__ = ["adaptive_law", "adaptive_tube", "alpha_step", "bump", "circumvent",
           "circumvent_from_bumps", "conflict_distance", "control", "controller_status",
           "controller_step", "error_transform", "exp", "implicit_alpha_root", "law", "law_status", "law_step",
           "log", "numpy_math", "open_bump_sum", "predicted_state", "reach_tube",
           "segment_progress", "segments_progress", "smooth_max",
           "smooth_max_pair", "trigger"]

Array = np.ndarray


def _libm(function, name: str):
    """Element-wise ``function`` from Python's ``math`` module (the C library's libm).

    numpy's own ``exp``/``log``/``tanh`` use SIMD kernels that differ from libm by an ulp
    or so; CasADi and the generated C call libm. Using libm here keeps the oracle's
    rounding identical where the formula is, so comparisons can be tight even where the
    outputs are ill-conditioned (narrow tubes, ``|e|`` near 1).
    """
    vectorized = np.vectorize(function, otypes=[float])

    def apply(x):
        x = np.asarray(x, dtype=float)
        return vectorized(x) if x.size else x.copy()

    apply.__name__ = name
    apply.__doc__ = (f"``{name}`` element-wise through libm (Python's ``math``), on an array of any "
                     "shape; NaN outside the function's domain.")
    return apply


def _safe(function, domain):
    def wrapped(x):
        return function(x) if domain(x) else math.nan
    return wrapped


_LIBM = {
    "exp": _libm(lambda v: math.exp(v) if v < 709.0 else math.inf, "exp"),
    "log": _libm(_safe(math.log, lambda v: v > 0), "log"),
    "log1p": _libm(_safe(math.log1p, lambda v: v > -1), "log1p"),
    "tanh": _libm(math.tanh, "tanh"),
}
_NUMPY = {"exp": np.exp, "log": np.log, "log1p": np.log1p, "tanh": np.tanh}
#: True inside :func:`numpy_math` (per thread and per asyncio task: a context variable).
_USE_NUMPY: contextvars.ContextVar[bool] = contextvars.ContextVar("stt_numpy_math",
                                                                    default=False)


def _dispatch(name: str):
    libm, fast = _LIBM[name], _NUMPY[name]

    def apply(x):
        return fast(x) if _USE_NUMPY.get() else libm(x)
    apply.__name__ = name
    apply.__doc__ = libm.__doc__ + f""" Inside :func:`numpy_math`, numpy's ufunc instead.

    Parameters
    ----------
    x : array_like, any shape
        The argument.

    Returns
    -------
    ndarray, the shape of ``x``
        ``{name}(x)``, NaN outside the domain.
    """
    return apply


exp = _dispatch("exp")
log = _dispatch("log")
log1p = _dispatch("log1p")
tanh = _dispatch("tanh")


def numpy_math_active() -> bool:
    """Whether :func:`numpy_math` is in force here (a cache of values computed with the
    oracle's kernels keys on it).

    Returns
    -------
    bool
    """
    return _USE_NUMPY.get()


@contextlib.contextmanager
def numpy_math():
    """Within this context, evaluate ``exp``/``log``/``log1p``/``tanh`` with numpy's ufuncs.

    numpy's kernels differ from libm by an ulp or so and are tens of times faster on
    arrays; the certificate (:mod:`stt_codegen.design.certificate`), whose margins are
    far above rounding, evaluates the oracle's formulas this way. The switch is a context
    variable, so other threads (and asyncio tasks) keep libm.

    Yields
    ------
    None
        The body of the ``with`` statement runs with numpy's kernels and numpy's floating
        point warnings silenced.
    """
    token = _USE_NUMPY.set(True)
    try:
        with np.errstate(over="ignore", under="ignore", divide="ignore", invalid="ignore"):
            yield
    finally:
        _USE_NUMPY.reset(token)


def _time(t) -> Array:
    return np.atleast_1d(np.asarray(t, dtype=float))


def _rows(value, n_rows: int, width: int) -> Array:
    return np.broadcast_to(np.asarray(value, dtype=float), (n_rows, width))


def segment_progress(segment: ReachSegment, t) -> tuple[Array, Array]:
    """Profile ``p(tau)`` of one reach segment and ``dp/dt``; 0 before ``start``, 1 from ``end`` on.

    ``"tanh"``: ``p = tanh((t - start) / (end - t))`` (eq. (4), ``tau / (1 - tau)`` written
    so that a segment starting at 0 evaluates exactly the paper's ``t / (t_c - t)``);
    ``"smoothstep"``: ``p = tau^3 (10 - 15 tau + 6 tau^2)``,
    ``tau = (t - start) / (end - start)``; ``"cruise"``: the rate ``dp/dtau`` rises as
    ``v s(tau / a)`` (``s(x) = 3 x^2 - 2 x^3``, ``a = CRUISE_RAMP``, ``v = 1 / (1 - a)``),
    holds ``v``, falls as ``v s((1 - tau) / a)``; ``p`` is its integral from 0, and by
    the symmetry ``p(tau) = 1 - p(1 - tau)`` on the last ramp; ``"scurve"``: the
    acceleration ``d^2p/dtau^2`` is ``A u / q`` for ``u < q``, ``A`` up to ``1/2 - q``, ``A
    (1/2 - u) / q`` up to the middle (``u = min(tau, 1 - tau)``, ``q = SCURVE_TURN``, ``A = 4
    / (1 - 2 q)``, negated on the second half), so the rate is ``A u^2 / (2 q)``, ``A (u -
    q / 2)``, ``2 - A (1/2 - u)^2 / (2 q)``; ``p`` its integral, and ``1 - p(1 - tau)`` on
    the second half; ``"glide"``: the acceleration is ``A u / q`` for ``u < q``, ``A`` up to
    ``r - q``, ``A (r - u) / q`` up to ``r`` and 0 after (``r = GLIDE_RAMP``, ``q =
    GLIDE_TURN``, ``V = 1 / (1 - r)``, ``A = V / (r - q)``, negated on the second half), so the
    rate rises to ``V`` over the ramp and holds it; ``p`` its integral, and ``1 - p(1 - tau)``
    on the second half.

    Parameters
    ----------
    segment : ReachSegment
    t : array_like, shape (N,)
        Time, seconds.

    Returns
    -------
    p, p_dot : ndarray, shape (N,)
        Dimensionless and 1/s.
    """
    return _progress(segment.profile, _time(t), segment.start, segment.end)


def segments_progress(segments: Sequence[ReachSegment], t) -> Array:
    """:func:`segment_progress`'s ``p`` of many segments, each at its own row of times,
    one evaluation per profile (the same operations on every element as one segment at a
    time).

    Parameters
    ----------
    segments : sequence of ReachSegment, length S
    t : array_like, shape (S, N)
        Row ``k`` the times of segment ``k``, seconds.

    Returns
    -------
    ndarray, shape (S, N)
        Dimensionless.
    """
    t = np.asarray(t, dtype=float)
    profiles = [seg.profile for seg in segments]
    start = np.array([seg.start for seg in segments])[:, None]
    end = np.array([seg.end for seg in segments])[:, None]
    if len(set(profiles)) == 1:
        return _progress(profiles[0], t, start, end, rate=False)[0]
    p = np.empty(t.shape)
    for profile in sorted(set(profiles)):
        rows = [k for k, name in enumerate(profiles) if name == profile]
        p[rows] = _progress(profile, t[rows], start[rows], end[rows], rate=False)[0]
    return p


def _progress(profile: str, t: Array, start, end, rate: bool = True) -> tuple[Array, Array]:
    """:func:`segment_progress` of segments of one ``profile``: ``start`` and ``end`` are
    floats or arrays shaped like ``t`` (each point's own segment); the same operations on
    every element either way. Without ``rate``, ``p_dot`` is ``None``."""
    if profile == TANH:
        active = (t >= start) & (t < end)
        gap = np.where(active, end - t, 1.0)
        arg = np.where(active, (t - start) / gap, 0.0)
        p = np.where(t >= end, 1.0, np.where(active, tanh(arg), 0.0))
        if not rate:
            return p, None
        # sech^2(a) = 4 exp(-2a) / (1 + exp(-2a))^2 for a >= 0, written without cancellation.
        q = exp(-2.0 * np.abs(arg))
        sech2 = 4.0 * q / (1.0 + q) ** 2
        p_dot = np.where(active, sech2 * (end - start) / gap**2, 0.0)
        return p, p_dot
    duration = end - start
    tau = np.minimum(np.maximum((t - start) / duration, 0.0), 1.0)     # clip to [0, 1]
    if profile == SMOOTHSTEP:
        p = tau * tau * tau * (10.0 - 15.0 * tau + 6.0 * tau * tau)
        if not rate:
            return p, None
        p_dot = 30.0 * tau**2 * (1.0 - tau) ** 2 / duration
        return p, p_dot
    if profile == SCURVE:
        return _scurve(tau, duration, rate)
    if profile == GLIDE:
        return _glide(tau, duration, rate)
    if profile != CRUISE:
        raise ValueError(f"unknown reach segment profile {profile!r}")
    a = CRUISE_RAMP
    v = 1.0 / (1.0 - a)
    rising, falling = tau < a, tau > 1.0 - a
    x = np.where(rising, tau / a, np.where(falling, (1.0 - tau) / a, 1.0))
    # integral of v s over a ramp's first x: v a (x^3 - x^4 / 2)
    covered = v * a * x**3 * (1.0 - 0.5 * x)
    p = np.where(rising, covered, np.where(falling, 1.0 - covered, v * (tau - 0.5 * a)))
    if not rate:
        return p, None
    p_dot = v * x**2 * (3.0 - 2.0 * x) / duration
    # outside the segment tau is clamped to 0 or 1, where x = 0: the rate is 0 there
    return p, p_dot


def _scurve(tau: Array, duration, rate: bool) -> tuple[Array, Array]:
    """The ``"scurve"`` profile at ``tau`` in ``[0, 1]`` (:func:`segment_progress`), from its
    acceleration, integrated by hand on each piece of the first half."""
    q = SCURVE_TURN
    peak = 4.0 / (1.0 - 2.0 * q)
    first = tau <= 0.5
    u = np.where(first, tau, 1.0 - tau)
    rising, turning = u <= q, u > 0.5 - q
    w = 0.5 - u
    half = np.where(rising, peak * u**3 / (6.0 * q),
                    np.where(turning, 0.5 - 2.0 * w + peak * w**3 / (6.0 * q),
                             peak * (0.5 * u * u - 0.5 * q * u + q * q / 6.0)))
    p = np.where(first, half, 1.0 - half)
    if not rate:
        return p, None
    slope = np.where(rising, peak * u * u / (2.0 * q),
                     np.where(turning, 2.0 - peak * w * w / (2.0 * q), peak * (u - 0.5 * q)))
    return p, slope / duration


def _glide(tau: Array, duration, rate: bool) -> tuple[Array, Array]:
    """The ``"glide"`` profile at ``tau`` in ``[0, 1]`` (:func:`segment_progress`): the rate
    of each piece of the first ramp integrated by hand, the cruise at the rate ``V``."""
    r, q = GLIDE_RAMP, GLIDE_TURN
    top = 1.0 / (1.0 - r)
    peak = top / (r - q)
    first = tau <= 0.5
    u = np.where(first, tau, 1.0 - tau)
    rising, holding, easing = u <= q, u <= r - q, u <= r
    w = r - u
    half = np.where(rising, peak * u**3 / (6.0 * q),
                    np.where(holding, peak * (0.5 * u * u - 0.5 * q * u + q * q / 6.0),
                             np.where(easing, top * (0.5 * r - w) + peak * w**3 / (6.0 * q),
                                      top * (u - 0.5 * r))))
    p = np.where(first, half, 1.0 - half)
    if not rate:
        return p, None
    slope = np.where(rising, peak * u * u / (2.0 * q),
                     np.where(holding, peak * (u - 0.5 * q),
                              np.where(easing, top - peak * w * w / (2.0 * q), top)))
    return p, slope / duration


@functools.lru_cache(maxsize=64)
def _segment_table(segments: tuple[ReachSegment, ...]) -> tuple:
    """Per-segment arrays of :func:`reach_tube`: ends, starts (S,), and the bounds' start
    values and moves ``to - from`` (S, n) each, lower then upper; built once per tube."""
    starts = np.array([seg.start for seg in segments])
    ends = np.array([seg.end for seg in segments])
    lower_from = np.array([seg.lower_from for seg in segments], dtype=float)
    upper_from = np.array([seg.upper_from for seg in segments], dtype=float)
    lower_move = np.array([seg.lower_to for seg in segments], dtype=float) - lower_from
    upper_move = np.array([seg.upper_to for seg in segments], dtype=float) - upper_from
    for array in (starts, ends, lower_from, upper_from, lower_move, upper_move):
        array.setflags(write=False)
    return starts, ends, lower_from, upper_from, lower_move, upper_move


def reach_tube(design: TubeDesign, t, rates: bool = True) -> tuple[Array, Array, Array, Array]:
    """Reachability tube ``rho_L``, ``rho_U`` (eq. (4), piecewise) and their time derivatives.

    On segment ``k`` (the first whose ``end`` is after ``t``; the last one after every
    end) ``rho = from + (to - from) p(tau)``, see :func:`segment_progress`; where segment
    ``k + 1`` has started (a blended corner), plus ``(to - from) p(tau)`` of segment ``k + 1``.

    Parameters
    ----------
    design : TubeDesign
    t : array_like, shape (N,)
    rates : bool
        Also the derivatives (else ``None`` in their place).

    Returns
    -------
    rho_L, rho_U, rho_L_dot, rho_U_dot : ndarray, shape (N, n)
        State units and state units per second.
    """
    t = _time(t)
    segments = design.segments
    starts, ends, lower_from, upper_from, lower_move, upper_move = _segment_table(segments)
    if len(segments) == 1:
        s, s_dot = _progress(segments[0].profile, t, segments[0].start, segments[0].end,
                             rates)
        values = (lower_move[0] * s[:, None] + lower_from[0],
                  upper_move[0] * s[:, None] + upper_from[0])
        if not rates:
            return values[0], values[1], None, None
        return (*values, lower_move[0] * s_dot[:, None], upper_move[0] * s_dot[:, None])
    which = np.minimum(np.searchsorted(ends, t, side="right"), len(segments) - 1)
    profiles = {seg.profile for seg in segments}
    if len(profiles) == 1:
        # every point with its own segment's start and end: one evaluation for all
        s, s_dot = _progress(segments[0].profile, t, starts[which], ends[which], rates)
    else:
        s, s_dot = np.zeros(t.size), np.zeros(t.size)
        for profile in sorted(profiles):
            here = np.isin(which, [k for k, seg in enumerate(segments)
                                   if seg.profile == profile])
            s[here], s_dot[here] = _progress(profile, t[here], starts[which[here]],
                                             ends[which[here]])
    s = s[:, None]
    values = (lower_move[which] * s + lower_from[which], upper_move[which] * s + upper_from[which])
    moved = (lower_move[which] * s_dot[:, None], upper_move[which] * s_dot[:, None]) \
        if rates else (None, None)
    if design.blends_corners:
        _add_started(segments, t, which, (lower_move, upper_move), values, moved)
    return (*values, *moved)


def _add_started(segments, t: np.ndarray, which: np.ndarray, moves: tuple, values: tuple,
                 rates: tuple) -> None:
    """Add, in place, the move of the segment after each point's own where it has started
    (a blended corner: ``rho = from_k + (to_k - from_k) p_k + (to_{k+1} - from_{k+1})
    p_{k+1}`` on ``[start_{k+1}, end_k]``)."""
    following = which + 1
    starts = np.array([seg.start for seg in segments] + [np.inf])
    started = np.flatnonzero(starts[following] < t)
    for k in np.unique(following[started]):
        here = started[following[started] == k]
        seg = segments[k]
        s, s_dot = _progress(seg.profile, t[here], seg.start, seg.end, rates[0] is not None)
        for value, rate, move in zip(values, rates, moves):
            value[here] += move[k] * s[:, None]
            if rate is not None:
                rate[here] += move[k] * s_dot[:, None]


def bump(t, center: float, radius: float, sharpness: float) -> tuple[Array, Array]:
    """The bump of eqs. (7)-(8), ``exp(-k (t-m)^2 / (r^2 - (t-m)^2))`` in ``|t-m| < r``, else 0.

    Parameters
    ----------
    t : array_like, shape (N,)
    center, radius, sharpness : float
        ``m^j``, ``r^j`` (positive) and ``k^j``.

    Returns
    -------
    b, b_dot : ndarray, shape (N,)
        Value in ``[0, 1]`` and its time derivative, 1/s.
    """
    t = _time(t)
    d = t - center
    inside = np.abs(d) < radius
    # (r - |d|)(r + |d|): strictly positive wherever |d| < r holds in floating point
    denom = np.where(inside, (radius - np.abs(d)) * (radius + np.abs(d)), 1.0)
    b = np.where(inside, exp(-sharpness * d**2 / denom), 0.0)
    b_dot = np.where(inside, b * (-sharpness) * 2.0 * d * radius**2 / denom**2, 0.0)
    return b, b_dot


def smooth_max(values: Array, nu: float, axis: int = -1) -> tuple[Array, Array]:
    """The paper's smooth max ``(1/nu) ln(sum_j exp(nu a_j))`` (eq. (10)) and its weights.

    Evaluated without overflow: ``max(a, b) + log1p(exp(-nu |a - b|)) / nu`` for two
    values, ``M + ln(sum_j exp(nu (a_j - M))) / nu`` with ``M = max_j a_j`` for more.

    Parameters
    ----------
    values : array_like
        The ``a_j`` along ``axis``, state units.
    nu : float
        Smoothness ``nu > 0`` of eq. (10); larger is closer to ``max``.
    axis : int
        The axis reduced.

    Returns
    -------
    value : ndarray
        ``values`` reduced over ``axis``.
    weights : ndarray
        ``d value / d a_j = exp(nu (a_j - value))`` (non-negative, summing to 1).
    """
    values = np.moveaxis(np.asarray(values, dtype=float), axis, -1)
    count = values.shape[-1]
    if count == 1:
        value = values[..., 0]
    elif count == 2:
        value = smooth_max_pair(values[..., 0], values[..., 1], nu)
    else:
        top = values.max(axis=-1)
        total = np.zeros_like(top)
        for j in range(count):
            total = total + exp(nu * (values[..., j] - top))
        value = top + log(total) / nu
    weights = exp(nu * (values - value[..., None]))
    return value, np.moveaxis(weights, -1, axis)


def smooth_max_pair(a: Array, b: Array, nu: float) -> Array:
    """:func:`smooth_max` of two values, without its weights: ``max(a, b) + log1p(exp(-nu |a - b|)) / nu``.

    Parameters
    ----------
    a, b : ndarray, the same shape
        State units.
    nu : float
        Smoothness ``nu > 0`` of eq. (10).

    Returns
    -------
    ndarray, the shape of ``a``
        ``(1/nu) ln(exp(nu a) + exp(nu b))``, state units.
    """
    return np.maximum(a, b) + log1p(exp(-nu * np.abs(a - b))) / nu


def open_bump_sum(heights: Array, nu: float, weights: bool = True) -> tuple[Array, Array]:
    """``F_nu(y) = (1/nu) ln(1 + sum_j (exp(nu y_j) - 1))``, the combination of eq. (9).

    Evaluated without overflow as
    ``M + (1/nu) ln(exp(-nu M) + sum_j (exp(nu (y_j - M)) - exp(-nu M)))``,
    ``M = max(0, max_j y_j)``; with one argument ``F = y`` exactly. A closed window
    (``y_j = 0``) contributes exactly 0. ``F`` is non-decreasing and C-infinity in every
    ``y_j``, ``F = 0`` when every ``y_j = 0`` and ``max(0, y) <= F <= max(0, y) + ln(m)/nu``.

    Parameters
    ----------
    heights : ndarray, shape (..., m)
        ``y_j = B^j b^j(t) >= 0``, state units, ``m >= 1``.
    nu : float
        ``nu``, 1/state units.
    weights : bool
        Also the weights (else ``None`` in their place).

    Returns
    -------
    value : ndarray, shape (...)
    weights : ndarray, shape (..., m)
        ``dF / dy_j = exp(nu (y_j - F))``, in ``(0, 1]``.
    """
    y = np.asarray(heights, dtype=float)
    if y.shape[-1] == 1:
        value = y[..., 0]
    else:
        top = np.maximum(y.max(axis=-1), 0.0)
        floor = exp(-nu * top)
        total = floor.copy()
        for j in range(y.shape[-1]):
            total = total + (exp(nu * (y[..., j] - top)) - floor)
        value = top + log(total) / nu
    if not weights:
        return value, None
    return value, exp(nu * (y - value[..., None]))


def circumvent_from_bumps(design: TubeDesign, bumps: list,
                          count: int, weights: bool = True) -> tuple[Array, Array, list]:
    """Eq. (9) from given bump values: ``beta_L``, ``beta_U`` and each circumvent's weight.

    ``beta_L_i = X_i + F_nu(y)`` and ``beta_U_i = X-bar_i - F_nu(y)`` with
    ``y_j = B^j b^j`` over the circumvents on that bound (:func:`open_bump_sum`), so
    ``beta_L`` is non-decreasing and ``beta_U`` non-increasing in every bump value.

    Parameters
    ----------
    design : TubeDesign
    bumps : list of ndarray, shape (N,) each
        The bump value of each of ``design.circumvents``, in that order.
    count : int
        ``N``.
    weights : bool
        Also the weights (else a list of ``None``).

    Returns
    -------
    beta_L, beta_U : ndarray, shape (N, n)
    weights : list of ndarray, shape (N,) each
        ``|d beta / d (B^j b^j)|``, aligned with ``design.circumvents``.
    """
    out_weights: list = [None] * len(design.circumvents)
    out = []
    for side, bounds, sign in ((LOWER, design.state_lower, 1.0),
                               ("upper", design.state_upper, -1.0)):
        value = np.empty((count, len(bounds)))
        value[:] = bounds                       # the bound, on every row
        for i in range(design.dimension):
            members = [j for j, c in enumerate(design.circumvents)
                       if c.dimension == i and c.side == side]
            if not members:
                continue
            c = design.circumvents
            y = np.stack([c[j].height * np.asarray(bumps[j], dtype=float)
                          for j in members], axis=-1)
            f, w = open_bump_sum(y, design.smoothness, weights)
            value[:, i] = bounds[i] + sign * f
            for k, j in enumerate(members):
                out_weights[j] = None if w is None else w[..., k]
        out.append(value)
    return out[0], out[1], out_weights


def circumvent(design: TubeDesign, t, rates: bool = True) -> tuple[Array, Array, Array, Array]:
    """Holistic circumvent function ``beta_L``, ``beta_U`` of eq. (9) and derivatives.

    Bumps on the same bound are combined by :func:`open_bump_sum`; a bound with no bump
    is the state-space bound.

    Parameters
    ----------
    design : TubeDesign
        The tube (its circumvents and state-space bounds).
    t : float or array_like, shape (N,)
        Times, s.
    rates : bool
        Also the derivatives (else ``None`` in their place).

    Returns
    -------
    beta_L, beta_U, beta_L_dot, beta_U_dot : ndarray, shape (N, n)
    """
    t = _time(t)
    n = design.dimension
    pairs = [bump(t, c.center, c.radius, c.sharpness) for c in design.circumvents]
    beta_l, beta_u, weights = circumvent_from_bumps(design, [b for b, _ in pairs], t.size,
                                                    rates)
    if not rates:
        return beta_l, beta_u, None, None
    rate_l, rate_u = np.zeros((t.size, n)), np.zeros((t.size, n))
    for c, (_, b_dot), w in zip(design.circumvents, pairs, weights):
        if c.side == LOWER:
            rate_l[:, c.dimension] += w * c.height * b_dot
        else:
            rate_u[:, c.dimension] -= w * c.height * b_dot
    return beta_l, beta_u, rate_l, rate_u


def conflict_distance(design: TubeDesign, t) -> Array:
    """``psi = [beta_U - rho_L, rho_U - beta_L]`` of eq. (11), shape (N, 2n).

    Parameters
    ----------
    design : TubeDesign
        The tube.
    t : float or array_like, shape (N,)
        Times, s.

    Returns
    -------
    ndarray, shape (N, 2n)
        ``psi``, state units; positive where the reach tube and the circumvent do not conflict.
    """
    rho_l, rho_u, _, _ = reach_tube(design, t, rates=False)
    beta_l, beta_u, _, _ = circumvent(design, t, rates=False)
    return np.concatenate([beta_u - rho_l, rho_u - beta_l], axis=1)


def trigger(design: TubeDesign, psi) -> Array:
    """The trigger of the adaptive law (11), ``theta = theta0 (1 - tanh(psi - mu))``.

    ``sign`` is approximated by ``tanh`` with unit slope, as the paper says.

    Parameters
    ----------
    design : TubeDesign
        The tube (``theta0``, ``mu``).
    psi : array_like, any shape
        ``psi`` of eq. (11), state units.

    Returns
    -------
    ndarray, the shape of ``psi``
        In ``[0, 2 theta0]``.
    """
    return design.theta0 * (1.0 - tanh(np.asarray(psi, dtype=float) - design.mu))


def adaptive_law(design: TubeDesign, t, alpha) -> tuple[Array, Array]:
    """Adaptive law (11): ``alpha_dot = theta / (psi + alpha)^2 - kappa alpha``.

    ``theta = theta0 (1 - tanh(psi - mu))`` (``sign`` approximated by ``tanh``).

    Parameters
    ----------
    design : TubeDesign
        The tube (``theta0``, ``mu``, ``kappa``).
    t : array_like, shape (N,)
    alpha : array_like, shape (N, 2n)
        ``[alpha_L, alpha_U]``, valid where ``psi + alpha > 0``.

    Returns
    -------
    alpha_dot : ndarray, shape (N, 2n)
    alpha_dot_jacobian : ndarray, shape (N, 2n)
        The diagonal of ``d alpha_dot / d alpha``: ``-2 theta / (psi + alpha)^3 - kappa``.
    """
    t = _time(t)
    psi = conflict_distance(design, t)
    return _alpha_rate(design, psi, _rows(alpha, t.size, psi.shape[1]))


def _alpha_rate(design: TubeDesign, psi: Array, alpha: Array) -> tuple[Array, Array]:
    """:func:`adaptive_law` at given ``psi`` (N, 2n) and ``alpha`` (N, 2n)."""
    theta = trigger(design, psi)
    z = psi + alpha
    return theta / z**2 - design.kappa * alpha, -2.0 * theta / z**3 - design.kappa


def adaptive_tube(design: TubeDesign, t, alpha) -> tuple[Array, Array, Array, Array]:
    """Adaptive tube (10): ``gamma_L = max~(rho_L - alpha_L, beta_L)``, ``gamma_U = min~(rho_U + alpha_U, beta_U)``.

    The derivatives are total time derivatives along the adaptive law (11).

    Parameters
    ----------
    design : TubeDesign
        The tube.
    t : float or array_like, shape (N,)
        Times, s.
    alpha : array_like, shape (N, 2n)
        ``[alpha_L, alpha_U]`` of eq. (11), state units.

    Returns
    -------
    gamma_L, gamma_U, gamma_L_dot, gamma_U_dot : ndarray, shape (N, n)
    """
    t = _time(t)
    n = design.dimension
    rho_l, rho_u, rho_l_dot, rho_u_dot = reach_tube(design, t)
    beta_l, beta_u, beta_l_dot, beta_u_dot = circumvent(design, t)
    alpha = _rows(alpha, t.size, 2 * n)
    # adaptive_law with the psi of the pieces at hand (conflict_distance's operations)
    psi = np.concatenate([beta_u - rho_l, rho_u - beta_l], axis=1)
    alpha_dot, _ = _alpha_rate(design, psi, alpha)
    nu = design.smoothness
    gamma_l, w_l = smooth_max(np.stack([rho_l - alpha[:, :n], beta_l], -1), nu)
    neg_u, w_u = smooth_max(np.stack([-(rho_u + alpha[:, n:]), -beta_u], -1), nu)
    gamma_l_dot = w_l[..., 0] * (rho_l_dot - alpha_dot[:, :n]) + w_l[..., 1] * beta_l_dot
    gamma_u_dot = w_u[..., 0] * (rho_u_dot + alpha_dot[:, n:]) + w_u[..., 1] * beta_u_dot
    return gamma_l, -neg_u, gamma_l_dot, gamma_u_dot


def error_transform(design: TubeDesign, x, t, alpha) -> tuple[Array, Array, Array, Array]:
    """Normalized error ``e``, transformed error ``epsilon`` and ``xi`` of section IV.

    ``e = gamma_d^{-1} (2 x - gamma_s)``, ``epsilon_i = ln((1 + e_i) / (1 - e_i))``,
    ``xi = diag(4 / (gamma_d_i (1 - e_i^2)))`` (the element-wise reading of
    ``4 gamma_d^{-1} (I - e e^T)^{-1}``, see docs/decisions.md, decision 2).

    Parameters
    ----------
    design : TubeDesign
        The tube.
    x : array_like, shape (N, n)
    t : array_like, shape (N,)
    alpha : array_like, shape (N, 2n)

    Returns
    -------
    e, epsilon, xi : ndarray, shape (N, n)
    epsilon_jacobian : ndarray, shape (N, n, n)
        ``d epsilon / d x`` written out from the chain rule (diagonal).
    """
    t = _time(t)
    gamma_l, gamma_u, _, _ = adaptive_tube(design, t, alpha)
    x = _rows(x, t.size, design.dimension)
    gamma_d = gamma_u - gamma_l
    e = (2.0 * x - (gamma_u + gamma_l)) / gamma_d
    epsilon = log((1.0 + e) / (1.0 - e))
    xi = 4.0 / (gamma_d * (1.0 - e**2))
    d_eps_d_e = 1.0 / (1.0 + e) + 1.0 / (1.0 - e)
    jac = np.zeros((t.size, design.dimension, design.dimension))
    idx = np.arange(design.dimension)
    jac[:, idx, idx] = d_eps_d_e * 2.0 / gamma_d
    return e, epsilon, xi, jac


def control(design: TubeDesign, x, t, alpha) -> Array:
    """Control law (13): ``u = -k xi epsilon``, shape (N, n).

    Parameters
    ----------
    design : TubeDesign
        The tube (its gain ``k``).
    x : array_like, shape (N, n)
        State, state units.
    t : float or array_like, shape (N,)
        Times, s.
    alpha : array_like, shape (N, 2n)
        ``[alpha_L, alpha_U]``, state units.

    Returns
    -------
    ndarray, shape (N, n)
        ``u``, without clamps (NaN or infinite outside the tube).
    """
    _, epsilon, xi, _ = error_transform(design, x, t, alpha)
    return -design.gain * xi * epsilon


def implicit_alpha_root(alpha: Array, psi: Array, theta: Array, dt: Array,
                        kappa: float) -> Array:
    """Root of the backward-Euler equation of (11), ``a = alpha + dt (theta/(psi+a)^2 - kappa a)``.

    With ``c = 1 + kappa dt``, ``A = dt theta`` and ``z = psi + a`` the equation is
    ``c z^3 - (c psi + alpha) z^2 - A = 0``, whose positive root is unique and lies in
    ``[max(p/c, 0), max(p/c, 0) + (A/c)^(1/3)]``, ``p = c psi + alpha``; in ``a`` the
    bracket is also bounded below by ``alpha / c`` and ``-psi``. Solved by bisection to
    adjacent floating-point numbers.

    Parameters
    ----------
    alpha, psi, theta, dt : array_like, broadcastable
    kappa : float
        ``kappa`` of eq. (11), 1/s.

    Returns
    -------
    ndarray
    """
    alpha, psi, theta, dt = np.broadcast_arrays(*(np.asarray(v, dtype=float)
                                                  for v in (alpha, psi, theta, dt)))
    c = 1.0 + kappa * dt
    a_coef = dt * theta
    z_low = np.maximum((c * psi + alpha) / c, 0.0)
    lo = np.maximum(np.maximum(alpha / c, -psi), z_low - psi)
    hi = np.maximum(lo, z_low + np.cbrt(a_coef / c) - psi)

    def residual(a: Array) -> Array:
        with np.errstate(divide="ignore"):
            return c * a - alpha - a_coef / (psi + a) ** 2

    for _ in range(2100):  # never more than the doubles between lo and hi
        mid = 0.5 * (lo + hi)
        if np.all((mid == lo) | (mid == hi)):
            break
        below = residual(mid) < 0
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    return np.where(np.abs(residual(lo)) < np.abs(residual(hi)), lo, hi)


def alpha_step(design: TubeDesign, t, dt, alpha) -> Array:
    """Implicit (backward Euler) step of the adaptive law (11) from ``t`` to ``t + dt``.

    Parameters
    ----------
    design : TubeDesign
        The tube (``theta0``, ``mu``, ``kappa``).
    t, dt : array_like, shape (N,)
        Seconds; ``dt > 0``.
    alpha : array_like, shape (N, 2n)

    Returns
    -------
    alpha_next : ndarray, shape (N, 2n)
        :func:`implicit_alpha_root` with ``psi`` and ``theta`` at ``t + dt``.
    """
    t = _time(t)
    dt = np.broadcast_to(np.asarray(dt, dtype=float), t.shape)
    psi = conflict_distance(design, t + dt)
    alpha = _rows(alpha, t.size, psi.shape[1])
    theta = trigger(design, psi)
    return implicit_alpha_root(alpha, psi, theta, dt[:, None], design.kappa)


def law_step(design: TubeDesign, x, t, dt, alpha) -> tuple[Array, Array, Array]:
    """:func:`controller_step` before the actuator clamp: law (13)'s ``u`` (with the clamps
    of ``e`` and ``gamma_d``), shape (N, n), the next ``alpha`` (N, 2n) and ``inside`` (N,).

    Parameters
    ----------
    design : TubeDesign
        The tube.
    x : array_like, shape (N, n)
        State, state units.
    t : float or array_like, shape (N,)
        Times, s.
    dt : float or array_like, shape (N,)
        Steps, s, positive.
    alpha : array_like, shape (N, 2n)
        ``alpha`` at ``t``, state units.

    Returns
    -------
    u : ndarray, shape (N, n)
        Law (13) with the deployed clamps, before the actuator clamp.
    alpha_next : ndarray, shape (N, 2n)
        ``alpha`` at ``t + dt`` (:func:`alpha_step`).
    inside : ndarray, shape (N,)
        1.0 where ``x`` is strictly inside the tube, else 0.0.
    """
    t = _time(t)
    gamma_l, gamma_u, _, _ = adaptive_tube(design, t, alpha)
    x = _rows(x, t.size, design.dimension)
    u, inside = law(design.gain, x, gamma_l, gamma_u)
    return u, alpha_step(design, t, dt, alpha), inside


def law(gain: float, x, gamma_l, gamma_u) -> tuple[Array, Array]:
    """Law (13) in a known tube, with the deployed clamps of ``e`` (``E_MAX``) and of the
    width (``GAMMA_D_MIN``): ``u = -k xi epsilon``, shape (N, n), and ``inside`` (N,), 1.0
    where ``x`` is strictly inside ``(gamma_l, gamma_u)``.

    Parameters
    ----------
    gain : float
        ``k`` of (13).
    x, gamma_l, gamma_u : array_like, shape (N, n)
        State and tube bounds, state units.

    Returns
    -------
    u : ndarray, shape (N, n)
        The input.
    inside : ndarray, shape (N,)
        1.0 inside, else 0.0.
    """
    gamma_d = gamma_u - gamma_l
    width = np.maximum(gamma_d, GAMMA_D_MIN)
    e = (2.0 * x - (gamma_u + gamma_l)) / width
    inside = np.all((x > gamma_l) & (x < gamma_u), axis=1).astype(float)
    e_c = np.clip(e, -E_MAX, E_MAX)
    epsilon = log((1.0 + e_c) / (1.0 - e_c))
    xi = 4.0 / (width * (1.0 - e_c**2))
    return -gain * xi * epsilon, inside


def saturate(design: TubeDesign, u) -> tuple[Array, Array]:
    """The actuator clamp of ``[actuator] input_bound``: ``u`` limited to ``+-input_bound``.

    Parameters
    ----------
    design : TubeDesign
        Without an input bound the clamp is the identity.
    u : array_like, shape (N, n)
        Law (13)'s ``u``, input units.

    Returns
    -------
    u_clamped : ndarray, shape (N, n)
        Each entry moved to the nearest of ``[-input_bound_i, input_bound_i]``.
    within : ndarray, shape (N,)
        1.0 where no entry was moved (``|u_i| <= input_bound_i`` for every ``i``), else 0.0.
    """
    u = np.atleast_2d(np.asarray(u, dtype=float))
    if design.input_bound is None:
        return u, np.ones(u.shape[0])
    bound = np.array(design.input_bound)
    within = np.all(np.abs(u) <= bound, axis=1).astype(float)
    return np.clip(u, -bound, bound), within


def controller_step(design: TubeDesign, x, t, dt, alpha) -> tuple[Array, Array, Array]:
    """One step of the deployed controller: ``u`` at ``(x, t, alpha)`` and the next ``alpha``.

    ``u`` follows law (13) with ``e`` clamped to ``[-E_MAX, E_MAX]`` and ``gamma_d``
    floored at ``GAMMA_D_MIN``, so it is finite outside the tube too, and, for a design
    with an actuator bound, clamped to ``+-input_bound`` (:func:`saturate`). ``inside`` is
    ``gamma_L_i < x_i < gamma_U_i`` for every ``i``, two comparisons without rounding (the
    rounded ``|2 x_i - gamma_s_i| < gamma_d_i`` reported points on the bounds and one ulp
    outside as inside); an empty tube has no inside point.

    Parameters
    ----------
    design : TubeDesign
        The tube.
    x : array_like, shape (N, n)
        State, state units.
    t : float or array_like, shape (N,)
        Times, s.
    dt : float or array_like, shape (N,)
        Steps, s, positive.
    alpha : array_like, shape (N, 2n)
        ``alpha`` at ``t``, state units.

    Returns
    -------
    u : ndarray, shape (N, n)
    alpha_next : ndarray, shape (N, 2n)
    inside : ndarray, shape (N,)
        1.0 where ``gamma_L_i < x_i < gamma_U_i`` for every ``i``, else 0.0.
    """
    u, alpha_next, inside = law_step(design, x, t, dt, alpha)
    return saturate(design, u)[0], alpha_next, inside


def law_status(design: TubeDesign, x, t, dt, alpha) -> tuple[Array, Array, Array]:
    """:func:`controller_step` with the law's status code instead of ``inside``: the status
    of the generated ``P_control`` (which takes no ``dt``), the step's without its period
    check (:func:`controller_status`).

    Parameters
    ----------
    design : TubeDesign
        The tube.
    x : array_like, shape (N, n)
        State, state units.
    t : float or array_like, shape (N,)
        Times, s.
    dt : float or array_like, shape (N,)
        Steps, s, positive.
    alpha : array_like, shape (N, 2n)
        ``alpha`` at ``t``, state units.

    Returns
    -------
    u : ndarray, shape (N, n)
    alpha_next : ndarray, shape (N, 2n)
    status : ndarray of int, shape (N,)
        ``STATUS_OUTSIDE_TUBE`` where ``x`` is not strictly inside the tube, else
        ``STATUS_INPUT_CLAMPED`` where the actuator clamp moved an entry of ``u``, else
        ``STATUS_OK``.
    """
    u, alpha_next, inside = law_step(design, x, t, dt, alpha)
    u_c, within = saturate(design, u)
    status = np.where(inside == 0.0, STATUS_OUTSIDE_TUBE,
                      np.where(within == 0.0, STATUS_INPUT_CLAMPED, STATUS_OK))
    return u_c, alpha_next, status


def controller_status(design: TubeDesign, x, t, dt, alpha) -> tuple[Array, Array, Array]:
    """:func:`controller_step` with the status code of the generated step instead of
    ``inside``: :func:`law_status`'s, ``STATUS_OFF_PERIOD`` in place of ``OK`` and
    ``INPUT_CLAMPED`` where ``dt`` is not the period ``1 / rate_hz``
    (:func:`~stt_codegen.tube.parameters.step_status`).

    Parameters
    ----------
    design : TubeDesign
        The tube.
    x : array_like, shape (N, n)
        State, state units.
    t : float or array_like, shape (N,)
        Times, s.
    dt : float or array_like, shape (N,)
        Steps, s, positive.
    alpha : array_like, shape (N, 2n)
        ``alpha`` at ``t``, state units.

    Returns
    -------
    u : ndarray, shape (N, n)
    alpha_next : ndarray, shape (N, 2n)
    status : ndarray of int, shape (N,)
        ``STATUS_OUTSIDE_TUBE`` where ``x`` is not strictly inside the tube, else
        ``STATUS_OFF_PERIOD`` where ``dt`` is not the period, else ``STATUS_INPUT_CLAMPED``
        where the actuator clamp moved an entry of ``u``, else ``STATUS_OK``.
    """
    u_c, alpha_next, status = law_status(design, x, t, dt, alpha)
    return u_c, alpha_next, step_status(status, dt, design.rate_hz)


def predicted_state(x, held, step: float) -> np.ndarray:
    """The oracle's prediction of a first-order plant's state over a computation delay
    (docs/sampled-data.md, "Compensating a delay", eq. (P0)): ``x + step u_held``.

    Parameters
    ----------
    x : array_like, shape (N, n)
        States, state units.
    held : array_like, shape (N, n)
        The command acting at the read, input units.
    step : float
        ``delay g_mid``, s (times the gain's units).

    Returns
    -------
    ndarray, shape (N, n)
    """
    return np.asarray(x, dtype=float) + step * np.asarray(held, dtype=float)
