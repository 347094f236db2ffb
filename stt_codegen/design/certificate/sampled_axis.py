"""One axis of the sampled loop over one sampling interval: the per-axis interval argument.

Law (13) on axis ``i`` at ``|e_i| = s`` asks ``u_i = -(4 k / gamma_d,i) phi(s)`` (signed
with ``e_i``), with ``phi(s) = 2 atanh(s) / (1 - s^2)``. Held over ``[t_k, t_k + dt]``,
``x_i`` moves as ``x_dot_i = g_ii u_i + d_i`` with ``g_ii`` in ``[g_min, g_max]`` (a
diagonal entry of ``g`` is one of its symmetric part) and ``|d_i| <= D_i`` (drift,
disturbance and the other inputs through the coupling). :func:`axis_interval` encloses
``x_i`` over the interval and at its end for every ``e_i(t_k)`` in an interval
(docs/sampled-data.md, "The per-axis argument"). Plain floats: it runs once per axis and
sampling interval; the same formulas build the compiled loop of the cascade
(:mod:`.operations`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ...tube.parameters import GAMMA_D_MIN
from .operations import FLOATS

__all__ = ["start_box", "phi", "phi_scalar", "phi_slope", "phi_slope_scalar", "peak", "peak_scalar",
           "peak_for_box", "coupling_push", "axis_interval", "held_speed", "turned_gains",
           "turn_failure", "clamp_failure", "room_failure", "unprovable"]


def phi(s: np.ndarray) -> np.ndarray:
    """``phi(s) = 2 atanh(s) / (1 - s^2)``: ``|u_i| gamma_d,i / (4 k)`` of law (13) at
    ``|e_i| = s``; odd, increasing, convex on ``[0, 1)``.

    Parameters
    ----------
    s : ndarray
        ``|e_i|`` in ``[0, 1)``, any shape.

    Returns
    -------
    ndarray
        ``phi(s)``, the shape of ``s``.
    """
    return 2.0 * np.arctanh(s) / (1.0 - s * s)


def phi_slope(s: np.ndarray) -> np.ndarray:
    """``phi'(s) = (2 + 4 s atanh(s)) / (1 - s^2)^2``: even, increasing in ``|s|``,
    ``phi'(0) = 2``.

    Parameters
    ----------
    s : ndarray
        ``e_i`` in ``(-1, 1)``, any shape.

    Returns
    -------
    ndarray
        ``phi'(s)``, the shape of ``s``.
    """
    return (2.0 + 4.0 * s * np.arctanh(s)) / (1.0 - s * s) ** 2


def phi_scalar(s: float, ops=FLOATS) -> float:
    """:func:`phi` for one float (or one ``SX`` symbol).

    Parameters
    ----------
    s : float
        ``|e_i|`` in ``[0, 1)``.
    ops : optional
        :data:`~.operations.FLOATS` (default) or :data:`~.operations.SYMBOLS`.

    Returns
    -------
    float
        ``phi(s)``.
    """
    return 2.0 * ops.atanh(s) / (1.0 - s * s)


def phi_slope_scalar(s: float, ops=FLOATS) -> float:
    """:func:`phi_slope` for one float (or one ``SX`` symbol).

    Parameters
    ----------
    s : float
        ``e_i`` in ``(-1, 1)``.
    ops : optional
        :data:`~.operations.FLOATS` (default) or :data:`~.operations.SYMBOLS`.

    Returns
    -------
    float
        ``phi'(s)``; ``inf`` for ``|s| >= 1`` (its limit at the tube's edge, as
        :func:`phi_slope` gives at ``+-1``: a curvature bound that holds nowhere, so an
        argument using it fails rather than passes).
    """
    inside = abs(s) < 1.0
    if not ops.symbolic and not inside:
        return math.inf
    return ops.select(inside, (2.0 + 4.0 * s * ops.atanh(s)) / (1.0 - s * s) ** 2, math.inf)


def peak(ratio: np.ndarray) -> np.ndarray:
    """``s* = argmax_s (s - phi(s) / ratio)`` on ``[0, 1)``: ``phi'(s*) = ratio``, or 0
    where ``ratio <= phi'(0) = 2``. Bisection (``phi'`` is increasing), to 60 halvings.

    Parameters
    ----------
    ratio : ndarray
        ``h / (g_min p)``: half-width over the pull of the weakest gain, any shape.

    Returns
    -------
    ndarray
        ``s*`` in ``[0, 1)``, the shape of ``ratio``.
    """
    ratio = np.asarray(ratio, dtype=float)
    # each distinct ratio once (a tube's widths repeat): the same floats, fewer halvings
    values, where = np.unique(ratio, return_inverse=True)
    lo, hi = np.zeros_like(values), np.full_like(values, 1.0 - 1e-15)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        up = phi_slope(mid) < values
        lo, hi = np.where(up, mid, lo), np.where(up, hi, mid)
    return np.where(ratio <= 2.0, 0.0, lo[where.reshape(ratio.shape)])


def _peak_float(ratio: float) -> float:
    """:func:`peak_scalar` on floats: the same bisection with :func:`phi_slope_scalar`'s
    float operations written out in the loop (``mid < 1`` always, so its ``inf`` branch is
    never taken): the same doubles, without a call per halving (the differential drive's
    sampled check asks it per sample and axis)."""
    if not ratio > 2.0:
        return 0.0
    atanh = math.atanh
    lo, hi = 0.0, 1.0 - 1e-15
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if (2.0 + 4.0 * mid * atanh(mid)) / (1.0 - mid * mid) ** 2 < ratio:
            lo = mid
        else:
            hi = mid
    return lo


def peak_scalar(ratio: float, ops=FLOATS) -> float:
    """:func:`peak` for one float (or one ``SX`` symbol).

    Parameters
    ----------
    ratio : float
        ``h / (g_min p)``.
    ops : optional
        :data:`~.operations.FLOATS` (default) or :data:`~.operations.SYMBOLS`.

    Returns
    -------
    float
        ``s*`` in ``[0, 1)``.
    """
    if not ops.symbolic:
        return _peak_float(ratio)
    lo, hi = 0.0, 1.0 - 1e-15
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        up = phi_slope_scalar(mid, ops) < ratio
        if ops.symbolic:
            lo, hi = ops.select(up, mid, lo), ops.select(up, hi, mid)
        elif up:
            lo = mid
        else:
            hi = mid
    return ops.select(ratio > 2.0, lo, 0.0)


#: Relative room between ``phi'`` at an end of a range of ``s`` and the ratio, beyond which
#: :func:`peak_for_box` decides on which side of the range ``s*`` lies without bisecting:
#: far above the rounding of ``phi'``'s float formula (below ``1e-12`` relative for
#: ``s <= PEAK_DECIDED_UP_TO``).
PEAK_ROOM = 1e-9
#: The largest end of a range at which :func:`peak_for_box` decides without bisecting.
PEAK_DECIDED_UP_TO = 0.999


def peak_for_box(ratio: float, a: float, b: float) -> float:
    """A value of ``s*`` that :func:`axis_interval` clips to the same doubles as
    :func:`peak_scalar` ``(ratio)`` for ``e_i(t_k)`` in ``[a, b]``, without the bisection
    where the ranges of ``|e_i|`` of both signs lie clearly on one side of ``s*``.

    :func:`axis_interval` uses ``s*`` only clipped to the range of ``s = |e_i|`` of each
    sign, ``[max(a, 0), b]`` and ``[max(-b, 0), -a]`` (those not empty). ``phi'`` is
    increasing, so when ``phi'`` at a range's upper end is below the ratio by a relative
    :data:`PEAK_ROOM`, every ``s`` of the range has ``phi'(s) < ratio`` also in floats, and
    the bisection of :func:`peak_scalar` ends above the range (it is clipped to the upper
    end); when ``phi'`` at its lower end is above the ratio by as much, the bisection ends
    below it (clipped to the lower end). When every range is decided, the largest upper
    end of the ranges below ``s*`` (0 when none) is clipped to the same ends; else the
    bisection is run.

    Parameters
    ----------
    ratio : float
        ``h / (g_min pull)``, as :func:`peak_scalar`.
    a, b : float
        ``e_i(t_k)`` lies in ``[a, b]``, inside ``(-1, 1)``.

    Returns
    -------
    float
        ``s`` in ``[0, 1)``: clipped to either range, the same float as
        :func:`peak_scalar` ``(ratio)`` clipped to it.

    Examples
    --------
    >>> from stt_codegen.design.certificate.sampled_axis import peak_for_box, peak_scalar
    >>> peak_scalar(40.0) > 0.5, peak_for_box(40.0, -0.1, 0.2)
    (True, 0.2)
    """
    if not ratio > 2.0:
        return 0.0
    above = 0.0
    for s_a, s_b, empty in ((max(a, 0.0), b, b < max(a, 0.0)),
                            (max(-b, 0.0), -a, -a < max(-b, 0.0) or -a == 0.0)):
        if empty:
            continue
        if s_b <= PEAK_DECIDED_UP_TO and phi_slope_scalar(s_b) < ratio * (1.0 - PEAK_ROOM):
            above = max(above, s_b)            # s* above the range: clipped to s_b
        elif not phi_slope_scalar(s_a) > ratio * (1.0 + PEAK_ROOM):
            return _peak_float(ratio)          # s* may lie in the range: bisect
        # else s* lies below the range: any value up to s_a is clipped to s_a
    return above


def coupling_push(others: float, coupling: float, spread: float, skew: float,
                  own: float, ops=FLOATS) -> float:
    """A bound of the displacement the other inputs cause on axis ``i`` over one interval,
    whatever ``g_ii`` is, beyond what ``g_min`` (outward) or ``g_max`` (inward) of the own
    input leaves.

    ``others`` bounds ``dt |u_j|`` over the other axes of the block (Euclidean), ``own`` is
    ``dt |u_i|``. The off-diagonal part of row ``i`` of ``g`` is at most ``coupling``; it is
    also its symmetric part (at most ``sqrt(min(g_ii - g_min, g_max - g_ii) spread)`` by the
    Schur complement of ``g_s - g_min I >= 0`` and of ``g_max I - g_s >= 0``) plus its skew
    part (at most ``skew``). Maximizing ``-(g_ii - g_min) own + sqrt((g_ii - g_min) spread)
    others`` over ``g_ii`` gives ``spread others^2 / (4 own)`` when ``others <= 2 own``, else
    ``spread (others - own)`` (docs/sampled-data.md, eq. (A3)).

    Parameters
    ----------
    others, coupling, spread, skew, own : float
        As above; ``spread = g_max - g_min``.
    ops : optional
        :data:`~.operations.FLOATS` (default) or :data:`~.operations.SYMBOLS`.

    Returns
    -------
    float
        The bound, state units: the least of ``coupling others`` and the symmetric bound plus
        ``skew others``; 0 when ``others <= 0``.
    """
    def pushed():
        symmetric = ops.branch(others <= 2.0 * own,
                               lambda: spread * others * others / (4.0 * own),
                               lambda: spread * (others - own))
        return ops.fmin(coupling * others, symmetric + skew * others)

    return ops.branch(others <= 0.0, lambda: 0.0, pushed)


def axis_interval(a: float, b: float, c0: float, h0: float, pull: float, g_min: float,
                  g_max: float, s_peak: float, push: float, others: float = 0.0,
                  coupling: float = 0.0, skew: float = 0.0,
                  ops=FLOATS) -> tuple[float, float, float, float]:
    """Enclosures of ``x_i`` on ``[t_k, t_{k+1}]`` and at ``t_{k+1}``, for every
    ``e_i(t_k)`` in ``[a, b]``.

    ``sigma x_i(t_{k+1})`` lies in ``[I(s), O(s)]`` for ``s = |e_i(t_k)|`` of sign
    ``sigma``, with ``I(s) = sigma c0 + s h0 - g_max pull phi(s) - push - C(s)`` and
    ``O(s) = sigma c0 + s h0 - g_min pull phi(s) + push + C(s)``, where ``C(s)`` is
    :func:`coupling_push` with ``own = pull phi(s)``. Without ``C`` both are concave in
    ``s``, so ``min I`` is at an end of the range of ``s`` and ``max O`` at ``s*`` clipped
    to it; ``C`` decreases in ``s``, so it is taken at the range's lower end ``s_a``.
    ``x_i`` moves along a line between ``t_k`` and ``t_{k+1}``'s extremes, so the path lies
    between the start and the end.

    Parameters
    ----------
    a, b : float
        ``e_i(t_k)`` lies in ``[a, b]``, inside ``(-1, 1)``.
    c0, h0 : float
        The tube's centre and half-width on axis ``i`` at ``t_k``, state units.
    pull : float
        ``4 k dt / gamma_d,i``: ``dt |u_i| / phi(s)`` per unit of ``g_ii``.
    g_min, g_max : float
        Range of ``g_ii`` (of the eigenvalues of the symmetric part of ``g``).
    s_peak : float
        :func:`peak` of ``h0 / (g_min pull)``.
    push : float
        ``dt |f + w|`` bound, state units.
    others : float
        ``dt |u_j|`` over the other axes of the block, bound (0: none).
    coupling, skew : float
        Row coupling and skew bound of ``g`` (see :func:`coupling_push`).
    ops : optional
        :data:`~.operations.FLOATS` (default) or :data:`~.operations.SYMBOLS` (a sign whose
        range is empty is then selected away rather than skipped).

    Returns
    -------
    path_lo, path_hi, end_lo, end_hi : float
        ``x_i`` on the whole interval, and at ``t_{k+1}``, state units.
    """
    fmin, fmax = ops.fmin, ops.fmax
    spread = g_max - g_min
    path_lo = end_lo = math.inf
    path_hi = end_hi = -math.inf
    for sign, s_a, s_b in ((1.0, fmax(a, 0.0), b), (-1.0, fmax(-b, 0.0), -a)):
        empty = s_b < s_a if sign > 0 else ops.either(s_b < s_a, s_b == 0.0)
        if not ops.symbolic and empty:
            continue
        phi_a, phi_b = phi_scalar(s_a, ops), phi_scalar(s_b, ops)
        extra = push + coupling_push(others, coupling, spread, skew, pull * phi_a, ops)
        start_a, start_b = sign * c0 + s_a * h0, sign * c0 + s_b * h0
        s_star = fmin(fmax(s_peak, s_a), s_b)
        # phi at s_star: phi_a or phi_b when it is an end (the same float)
        phi_star = (phi_scalar(s_star, ops) if ops.symbolic else phi_a if s_star == s_a
                    else phi_b if s_star == s_b else phi_scalar(s_star))
        out_max = sign * c0 + s_star * h0 - pull * g_min * phi_star + extra
        in_min = fmin(start_a - pull * g_max * phi_a, start_b - pull * g_max * phi_b) - extra
        low, high = fmin(start_a, in_min), fmax(start_b, out_max)
        if sign < 0:
            low, high, in_min, out_max = -high, -low, -out_max, -in_min
        if ops.symbolic:       # an empty range adds nothing: its values moved to -+inf
            pad = ops.pad(empty, math.inf)
            low, in_min, high, out_max = low + pad, in_min + pad, high - pad, out_max - pad
        path_lo, path_hi = fmin(path_lo, low), fmax(path_hi, high)
        end_lo, end_hi = fmin(end_lo, in_min), fmax(end_hi, out_max)
    return path_lo, path_hi, end_lo, end_hi


def held_speed(i: int, block: tuple[int, ...], reach_prev: list[float] | None,
               speed_prev: list[float], gain: float, spread: float, skew: float,
               coupling: float, push: float, ops=FLOATS) -> float:
    """``M_i``: a bound of axis ``i``'s speed under the previous command ``u_{k-1}``, state
    units per second (docs/sampled-data.md, eq. (T1)).

    ``gain |u_{k-1,i}|`` plus the other inputs of the block through the row's off-diagonal
    part (at most ``min(coupling, spread / sqrt(2) + skew)``, eq. (A2)) plus ``|f + w|``.
    With ``gain = g_max`` it bounds the motion while the held command acts (a computation
    delay); with ``gain`` the largest ``|g_ii - g_mid|`` it bounds the error of a
    prediction made with ``g_mid`` (eq. (P1)). Before the first command acts the input is
    zero (``reach_prev`` is ``None``).

    Parameters
    ----------
    i : int
        The axis.
    block : tuple of int
        The axes of ``i``'s block of ``g``.
    reach_prev : list of float or None
        The bound of ``|e_j(t_{k-1})|`` per axis; ``None`` before the first command.
    speed_prev : list of float
        ``|u_{k-1,j}| / phi(|e_j|)`` per axis (``4 k / gamma_d``), 1/s per unit of ``phi``.
    gain, spread, skew, coupling : float
        The factor of the own input, ``g_max - g_min``, and the skew and row-coupling bounds
        of ``g``.
    push : float
        ``|f + w|`` bound, state units per second.
    ops : optional
        :data:`~.operations.FLOATS` (default) or :data:`~.operations.SYMBOLS`.

    Returns
    -------
    float
        ``M_i``, state units per second.
    """
    if reach_prev is None:
        return push
    own = speed_prev[i] * phi_scalar(reach_prev[i], ops)
    others = ops.sqrt(sum((speed_prev[j] * phi_scalar(reach_prev[j], ops)) ** 2
                          for j in block if j != i))
    return gain * own + ops.fmin(coupling, spread / math.sqrt(2.0) + skew) * others + push


def turned_gains(angle: float, g_min: float, g_max: float, skew: float, coupling: float,
                 ops=FLOATS) -> tuple[float, float, float, float]:
    """The input gain's bounds for a command computed at one heading and acting while the
    base turns by up to ``angle`` (docs/differential-drive.md, eq. (R1)).

    Parameters
    ----------
    angle : float
        The largest turn, rad.
    g_min, g_max, skew, coupling : float
        The class's bounds at the command's own heading.
    ops : optional
        :data:`~.operations.FLOATS` (default) or :data:`~.operations.SYMBOLS`.

    Returns
    -------
    g_min, g_max, skew, coupling : float
        The bounds over the turn; ``g_min <= 0`` (``-inf`` from a quarter turn on) when the
        turn leaves no positive gain.
    """
    norm = g_max + skew                                   # |g|_2 of the class
    low = ops.branch(angle < 0.5 * math.pi,
                     lambda: ops.cos(angle) * g_min - ops.sin(angle) * norm, lambda: -math.inf)
    side = ops.sin(angle) * norm
    return low, g_max + side, skew + side, coupling + side


def turn_failure(angle: float, rate: float, t: float) -> str:
    """The reason a sampled check fails when :func:`turned_gains` leaves no positive gain.

    Parameters
    ----------
    angle, rate, t : float
        The turn, rad; the bound of ``|omega|``, rad/s; the interval's start, s.

    Returns
    -------
    str
    """
    return (f"the heading may turn by {angle:.3g} rad in a sampling period at t = {t:.4f} s "
            f"(|omega| <= {rate:.3g} rad/s), which leaves no positive input gain for the "
            "command computed before it")


def clamp_failure(i: int, reach: float, t: float) -> str:
    """The reason a sampled check fails when the bound of ``|e_i(t_k)|`` passes ``E_MAX``.

    Parameters
    ----------
    i : int
        The axis.
    reach : float
        The bound of ``|e_i(t_k)|``.
    t : float
        ``t_k``, s.

    Returns
    -------
    str
    """
    return f"|e_{i}| may reach {reach:.6g} at t = {t:.4f} s, beyond the clamp E_MAX"


def room_failure(i: int, t: float, dt: float, room: float) -> str:
    """The reason a sampled check fails when the enclosure of ``x`` reaches the tube's edge.

    Parameters
    ----------
    i : int
        The axis.
    t, dt : float
        The interval's start and length, s.
    room : float
        The room left, half-widths (not positive).

    Returns
    -------
    str
    """
    return (f"a plant of the class may leave the tube in dimension {i} on "
            f"[{t:.4f}, {t + dt:.4f}] s (the enclosure of x reaches {-room:.3g} half-widths "
            "beyond its edge)")


def unprovable(g_min: float, width_min: float) -> str | None:
    """Why law (13)'s sampled check cannot even start on a tube, or ``None``.

    Parameters
    ----------
    g_min : float
        The class's least input gain (``input_gain[0]``).
    width_min : float
        The tube's least width at a sample, state units.

    Returns
    -------
    str or None
        The reason: a gain that is not positive (Assumption 2), or a width below
        ``GAMMA_D_MIN``.
    """
    if g_min <= 0:
        return ("input_gain[0] must be positive (Assumption 2): law (13) cannot pull the "
                "state back otherwise")
    if width_min < GAMMA_D_MIN:
        return f"the tube is narrower than GAMMA_D_MIN = {GAMMA_D_MIN:g} at a sample"
    return None


def start_box(e0: list[float], initial_error: Sequence[tuple[float, float]] | None
               ) -> list[list[float]]:
    """The enclosure of ``e(0)`` a check starts from: the point ``e0``, or
    ``initial_error`` (checked: ``n`` intervals inside ``(-1, 1)``)."""
    if initial_error is None:
        return [[v, v] for v in e0]
    box = [[float(lo), float(hi)] for lo, hi in initial_error]
    if len(box) != len(e0) or not all(-1.0 < lo <= hi < 1.0 for lo, hi in box):
        raise ValueError(f"initial_error = {box!r}: one interval [lo, hi] per dimension "
                         f"({len(e0)}), inside (-1, 1)")
    return box
