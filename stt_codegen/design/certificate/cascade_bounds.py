"""Bounds of the change of the cascade's virtual velocity ``r`` over one sampling interval,
along one trajectory: the two terms of the velocity stage that the position stage causes
(docs/second-order.md, "The sampled cascade (certificate)").

Each is written once, in the arithmetic of :mod:`.operations`: on floats, and on ``SX``
symbols for the compiled loop of :mod:`.cascade_step`.
"""

from __future__ import annotations

from .operations import FLOATS
from .sampled_axis import phi_scalar, phi_slope_scalar

__all__ = ["STEP_PIECES", "step_velocity_change", "virtual_velocity_change"]


def virtual_velocity_change(k1: float, h: float, e1_start: float, e1_path: float,
                            speed: float, tube_move: float, width_min: float,
                            width_max: float, ops=FLOATS) -> float:
    """A bound of ``|r(x1(t), t) - r(x1(t_k), t_k)|`` on ``[t_k, t_k + h]`` along one
    trajectory.

    ``r = -(4 k1 / gamma_d) phi(e1)`` (:func:`~.sampled_axis.phi`). With ``q = phi(e1) /
    gamma_d``, ``|q(t) - q_k| <= phi'(E) |e1(t) - e1_k| / W_min + phi(E_k) (1 / W_min - 1 /
    W_max)`` (mean value; ``phi'`` increases in ``|e|``), and ``e1(t) - e1_k = (2 dx1 -
    d gamma_s - e1_k d gamma_d) / gamma_d(t)`` with ``|dx1| <= h max |x2|``, ``|d gamma_s|,
    |d gamma_d| <= M`` (the spans of both bounds over the interval).

    Parameters
    ----------
    k1 : float
        Position gain.
    h : float
        Sampling period, s.
    e1_start : float
        ``E_k >= |e1(t_k)|``.
    e1_path : float
        ``E >= |e1(t)|`` on the interval, ``< 1``.
    speed : float
        Bound of ``|x2_i|`` on the interval.
    tube_move : float
        ``M``: span of ``gamma_L`` plus span of ``gamma_U`` over the interval.
    width_min, width_max : float
        Bounds of ``gamma_d`` over the interval, ``0 < width_min <= width_max``.
    ops : optional
        :data:`~.operations.FLOATS` (default) or :data:`~.operations.SYMBOLS`.

    Returns
    -------
    float
        Velocity units.
    """
    de1 = (2.0 * h * speed + (1.0 + e1_start) * tube_move) / width_min
    return 4.0 * k1 * (phi_slope_scalar(e1_path, ops) * de1 / width_min
                       + phi_scalar(e1_start, ops) * (1.0 / width_min - 1.0 / width_max))


#: Pieces the range of ``e1(t_k)`` is cut into for :func:`step_velocity_change`.
STEP_PIECES = 8


def step_velocity_change(k1: float, h: float, a: float, b: float, shift: float,
                         scale: float, reach: float, half_k: float, half_n: float,
                         other: float, ops=FLOATS) -> float:
    """A bound of ``|r(x1(t_{k+1}), t_{k+1}) - r(x1(t_k), t_k)|`` along one trajectory, for
    every ``e1(t_k)`` in ``[a, b]``, from the tube at the two samples (exact there).

    With ``alpha = h_k / h_n``, ``beta = (c_k - c_n) / h_n`` (``c``, ``h``: centre and
    half-width), ``e1(t_{k+1}) - e1(t_k) = m(e) + d``, ``m(e) = (alpha - 1) e + beta + h
    r_k(e) / h_n`` (``r_k(e) = -(2 k1 / h_k) phi(e)``) and ``|d| <= other / h_n``
    (``other >= h |z_k| + h^2 A / 2``). ``r_n(e') - r_k(e) = -(2 k1 / h_n) (phi(e') -
    phi(e)) - 2 k1 phi(e) (1 / h_n - 1 / h_k)``; ``m`` is bounded on each of
    :data:`STEP_PIECES` pieces of ``[a, b]`` by interval arithmetic (``phi`` increases),
    ``phi'`` at the largest ``|e|`` the piece and its step reach (at most ``reach < 1``,
    the next sample's bound of ``|e1|``).

    Parameters
    ----------
    k1 : float
    h : float
        Sampling period, s.
    a, b : float
        Range of ``e1(t_k)``.
    shift, scale : float
        ``beta`` and ``alpha`` above.
    reach : float
        Bound of ``|e1|`` at both samples, ``< 1``.
    half_k, half_n : float
        Half-widths of the tube at ``t_k``, ``t_{k+1}``.
    other : float
        State units.
    ops : optional
        :data:`~.operations.FLOATS` (default) or :data:`~.operations.SYMBOLS`.

    Returns
    -------
    float
        Velocity units.
    """
    fmin, fmax, select = ops.fmin, ops.fmax, ops.select
    pull = 2.0 * k1 * h / half_k
    h_ratio = 1.0 / half_n
    worst = 0.0
    edges = [a + (b - a) * j / STEP_PIECES for j in range(STEP_PIECES + 1)]
    # phi at each edge once (phi is odd: phi(|e|) = |phi(e)|); the same values as per piece
    phis = [phi_scalar(e, ops) for e in edges]
    stretch = 1.0 / half_n - 1.0 / half_k
    widen = abs(stretch)
    slope_k, other_n, tilt = 2.0 * k1 / half_n, other * h_ratio, scale - 1.0
    for j in range(STEP_PIECES):
        c, d = edges[j], edges[j + 1]
        lin_c, lin_d = tilt * c, tilt * d
        m_hi = fmax(lin_c, lin_d) + shift + h_ratio * (-pull * phis[j])
        m_lo = fmin(lin_c, lin_d) + shift + h_ratio * (-pull * phis[j + 1])
        move = fmax(abs(m_hi), abs(m_lo)) + other_n
        wide = fmax(abs(c), abs(d))
        phi_wide = select(abs(c) >= abs(d), abs(phis[j]), abs(phis[j + 1]))
        top = fmin(wide + move, reach)
        apart = slope_k * phi_slope_scalar(top, ops) * move + 2.0 * k1 * phi_wide * widen
        # the same change with the step's two causes kept together, signs and all:
        # phi(e + m) / h_n - phi(e) / h_k = phi'(xi) m / h_n + phi(e) (1 / h_n - 1 / h_k),
        # xi between e and e + m, each factor by its range on the piece; then the rest of
        # the step (|e1(t_{k+1}) - e - m| <= other / h_n) by phi' at the farthest |e| it
        # reaches, far < 1
        far = wide + move
        valid = far < 1.0
        p_lo, p_hi = c + fmin(m_lo, 0.0), d + fmax(m_hi, 0.0)
        steepest = phi_slope_scalar(select(valid, far, 0.0), ops)
        flattest = phi_slope_scalar(select(p_lo * p_hi <= 0.0, 0.0,
                                           select(valid, fmin(abs(p_lo), abs(p_hi)), 0.0)),
                                    ops)
        turned_lo = h_ratio * fmin(flattest * m_lo, steepest * m_lo) + fmin(
            phis[j] * stretch, phis[j + 1] * stretch)
        turned_hi = h_ratio * fmax(flattest * m_hi, steepest * m_hi) + fmax(
            phis[j] * stretch, phis[j + 1] * stretch)
        together = 2.0 * k1 * (fmax(abs(turned_lo), abs(turned_hi))
                               + steepest * other_n * h_ratio)
        worst = fmax(worst, select(valid, fmin(apart, together), apart))
    return worst
