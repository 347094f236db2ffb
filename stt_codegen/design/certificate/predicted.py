"""Sampled-data check of law (13) with the delay-compensating prediction.

With ``[controller] compensate_delay`` the deployed loop reads ``x(s_k)`` at ``s_k = k dt``,
predicts the state at ``a_k = s_k + delay`` from the command ``u_{k-1}`` that acts until
then, ``x_hat_k = x(s_k) + delay g_mid u_{k-1}`` (``g_mid`` the middle of the declared
``input_gain``), computes ``u_k`` by law (13) at ``(x_hat_k, t_k)`` and applies it on
``[a_k, a_{k+1}]``. The check below proves, for every plant of the class, that ``x`` stays
strictly inside the tube and ``x_hat`` inside ``[-E_MAX, E_MAX]`` of it at every sample
(docs/sampled-data.md, "Compensating a delay").
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .enclosures import enclose_tube
from .lyapunov import others_max
from .plant_class import PlantClass
from .sampled_axis import (axis_interval, held_speed, peak_for_box, phi_scalar, start_box,
                           turn_failure, turned_gains, unprovable)
from ..samples import TubeSamples
from ...tube.parameters import E_MAX, TubeDesign

__all__ = ["check_predicted"]


def _ahead(values: np.ndarray, pick) -> np.ndarray:
    """The worst (``pick``) of intervals ``k`` and ``k + 1``, per interval ``k``: an
    actuation interval ``[t_k + delay, t_{k+1} + delay]`` lies within ``[t_k, t_{k+2}]``."""
    return pick(values, np.concatenate([values[1:], values[-1:]]))


def check_predicted(design: TubeDesign, samples: TubeSamples, plants: PlantClass,
                    gain: float | None = None, *, delay: float,
                    initial_error: Sequence[tuple[float, float]] | None = None) -> tuple:
    """Prove that law (13) with the delay-compensating prediction keeps ``|e_i| < 1``.

    The argument (docs/sampled-data.md, "Compensating a delay", eqs. (P1)-(P3)): the
    prediction misses ``x(a_k)`` by at most ``eta_k,i = delay M'_i`` per axis, with ``M'``
    the held command's speed of :func:`~.sampled_axis.held_speed` at the factor
    ``max(g_max - g_mid, g_mid - g_min)`` (P1). So ``x`` on ``[a_k, a_{k+1}]`` lies in the
    per-axis enclosure of :func:`~.sampled_axis.axis_interval` started from the box of
    ``x_hat_k`` and widened by ``eta_k`` (P2), which must lie strictly inside the tube over
    intervals ``k`` and ``k + 1``; and ``x_hat_{k+1} = x_hat_k + (x(a_k) - x_hat_k) +
    int_{a_k}^{s_{k+1}} x_dot + delay g_mid u_k``, the share ``1 - delay / dt`` of the
    period under the class and the rest at ``g_mid`` exactly (P3).

    Parameters
    ----------
    design : TubeDesign
        Gives ``rate_hz``, ``x(0)`` and, unless ``gain`` is given, ``k`` of law (13).
    samples : TubeSamples
        The deployed tube at the design's rate.
    plants : PlantClass
        The plant bounds; ``input_gain[0] > 0`` is needed.
    gain : float, optional
        ``k`` to check instead of ``design.gain``.
    delay : float
        The computation delay, s, in ``(0, dt]``.
    initial_error : sequence of (float, float), optional
        An interval of ``e_i(0)`` per dimension in place of the point ``e(x(0))``
        (:func:`~.sampled.check_sampled`).

    Returns
    -------
    passed : bool
    level : float
        The proved bound of ``|e(x_hat_k)|`` at the samples.
    margin, time : float
        The least room to the tube's edge in half-widths, and where.
    dimension : int
    reason : str
        Empty when passed.
    abs_e : ndarray or None, shape (K + 1, n)
        The bound of ``|e(x_hat_k)|`` per sample when passed.

    Raises
    ------
    ValueError
        ``delay`` outside ``(0, dt]``.
    """
    a = plants.assumptions
    k_gain = design.gain if gain is None else float(gain)
    n = design.dimension
    dt = 1.0 / design.rate_hz
    if not 0.0 < delay <= dt * (1.0 + 1e-12):
        raise ValueError(f"delay = {delay!r} s must lie in (0, dt = {dt!r}] s")
    share = 1.0 - min(delay / dt, 1.0)            # of the period x_hat's step is uncertain
    g_mid = 0.5 * (a.input_gain[0] + a.input_gain[1])
    blocks = a.coupled_blocks(n)
    block_of = {i: b for b in blocks for i in b}
    lo, hi = samples.gamma_lower, samples.gamma_upper
    width = hi - lo

    def fail(reason: str, margin: float, t: float, i: int, level: float) -> tuple:
        return False, level, margin, t, i, reason, None

    reason = unprovable(a.input_gain[0], float(width.min()))
    if reason is not None:
        return fail(reason, -math.inf, 0.0, 0, math.nan)
    enclosure = enclose_tube(design, samples)
    count = len(enclosure.t_start)
    bounds = plants.on_intervals(enclosure, count)
    half, centre = 0.5 * width, 0.5 * (hi + lo)
    pull = (4.0 * dt * k_gain / width).tolist()           # dt |u| / phi per unit g
    half_l, centre_l = half.tolist(), centre.tolist()
    up_e = ((_ahead(enclosure.upper_min, np.minimum) - centre[:count]) / half[:count]).tolist()
    low_e = ((_ahead(enclosure.lower_max, np.maximum) - centre[:count]) / half[:count]).tolist()
    # interval k's bounds (the prediction, x_hat's step) and the worst of k, k + 1 (the
    # actuation interval)
    own = [v.tolist() for v in (bounds.g_min, bounds.g_max, bounds.skew, bounds.coupling,
                                bounds.push)]
    wide = [_ahead(v, p).tolist() for v, p in ((bounds.g_min, np.minimum),
                                               (bounds.g_max, np.maximum),
                                               (bounds.skew, np.maximum),
                                               (bounds.coupling, np.maximum),
                                               (bounds.push, np.maximum))]
    turn = a.input_gain_turn
    speeds: list[float] = []
    reach_prev = None
    box = start_box(((np.array(design.initial_state) - centre[0]) / half[0]).tolist(),
                     initial_error)
    # before the first command acts (t in [0, delay]) the input is zero
    start = [[lo - delay * own[4][0] / half_l[0][i], hi + delay * own[4][0] / half_l[0][i]]
             for i, (lo, hi) in enumerate(box)]
    worst, worst_t, worst_i = math.inf, 0.0, 0
    top = max(max(-lo, hi) for lo, hi in box)
    abs_e = []
    for k in range(count):
        t = float(samples.t[k])
        reach_e = [max(-x, y) for x, y in box]
        abs_e.append(reach_e)
        if max(reach_e) > E_MAX:
            i = int(np.argmax(reach_e))
            return fail(f"|e_{i}| of the predicted state may reach {max(reach_e):.6g} at "
                        f"t = {t:.4f} s, beyond the clamp E_MAX", -math.inf, t, i, top)
        h_k, c_k, p_k = half_l[k], centre_l[k], pull[k]
        g_lo, g_hi, sk, cp, push = (v[k] for v in own)
        w_lo, w_hi, w_sk, w_cp, w_push = (v[k] for v in wide)
        deviation = max(g_hi - g_mid, g_mid - g_lo)       # |g_ii - g_mid|, unturned
        miss = None                                       # (P1'): Euclidean, for a base
        mid_lo = mid_hi = g_mid                           # the predicted share's gain
        mid_side = 0.0
        if turn is not None:
            # the own command acts over [a_k, a_{k+1}], computed at s_k; the held one since
            # s_{k-1}: a turn over dt + delay (docs/differential-drive.md, (R1))
            speeds.append(math.sqrt(sum((p_k[i] / dt * phi_scalar(reach_e[i])) ** 2
                                        for i in range(n))))
            rate = turn[0] * max(speeds[-3:]) + turn[1]
            angle = (dt + delay) * rate
            # the prediction turns the held (v, omega) with the heading read at s_k: it
            # misses the point's motion by |g - g_mid| + 2 g_mid sin(turn / 2) per |u|
            miss = delay * ((deviation + sk + 2.0 * g_mid * math.sin(min(delay * rate, math.pi)
                                                                   / 2.0))
                            * (speeds[-2] if k > 0 else 0.0) + push)
            # and x_hat's own share is g_mid turned by the heading's change over a period
            mid_lo = g_mid * math.cos(dt * rate) if dt * rate < 0.5 * math.pi else -math.inf
            mid_side = g_mid * math.sin(min(dt * rate, 0.5 * math.pi))
            g_lo, g_hi, sk, cp = turned_gains(angle, g_lo, g_hi, sk, cp)
            w_lo, w_hi, w_sk, w_cp = turned_gains(angle, w_lo, w_hi, w_sk, w_cp)
            if min(g_lo, w_lo) <= 0.0:
                return fail(turn_failure(angle, rate, t), -math.inf, t, 0, top)
        e_lo, e_hi = share * g_lo + (1.0 - share) * mid_lo, share * g_hi + (1.0 - share) * mid_hi
        e_sk, e_cp = share * sk + (1.0 - share) * mid_side, share * cp + (1.0 - share) * mid_side
        if not e_lo > 0.0:
            return fail(f"the predicted state's step leaves no positive input gain at t = "
                        f"{t:.4f} s", -math.inf, t, 0, top)
        path, ends = [], []
        for i in range(n):
            # (P1): the prediction's miss, from the held command u_{k-1}
            eta = miss if miss is not None else delay * held_speed(
                i, block_of[i], reach_prev, [p / dt for p in pull[max(k - 1, 0)]], deviation,
                g_hi - g_lo, sk, cp, push)
            rest = [j for j in block_of[i] if j != i]
            others = (dt * 2.0 * k_gain * math.sqrt(others_max(
                [math.atanh(reach_e[j]) for j in rest], math.inf, [h_k[j] for j in rest]))
                if rest else 0.0)
            # (P2): x over the actuation interval, from x_hat widened by eta
            p_lo, p_hi, _, _ = axis_interval(
                box[i][0], box[i][1], c_k[i], h_k[i], p_k[i], w_lo, w_hi,
                peak_for_box(h_k[i] / (w_lo * p_k[i]), *box[i]), dt * w_push + eta,
                others, w_cp, w_sk)
            # (P3): x_hat at the next sample
            _, _, x_lo, x_hi = axis_interval(
                box[i][0], box[i][1], c_k[i], h_k[i], p_k[i], e_lo, e_hi,
                peak_for_box(h_k[i] / (e_lo * p_k[i]), *box[i]), share * dt * push + eta,
                others, e_cp, e_sk)
            path_e = [(p_lo - c_k[i]) / h_k[i], (p_hi - c_k[i]) / h_k[i]]
            if k == 0:
                path_e = [min(path_e[0], start[i][0]), max(path_e[1], start[i][1])]
            path.append(path_e)
            ends.append((x_lo, x_hi))
        reach_prev = reach_e
        for i in range(n):
            room = min(up_e[k][i] - path[i][1], path[i][0] - low_e[k][i])
            if room < worst:
                worst, worst_t, worst_i = room, t, i
            if room <= 0.0:
                return fail(f"a plant of the class may leave the tube in dimension {i} on "
                            f"[{t + delay:.4f}, {t + dt + delay:.4f}] s (the enclosure of x "
                            f"reaches {-room:.3g} half-widths beyond its edge)", room, t, i,
                            top)
        h_n, c_n = half_l[k + 1], centre_l[k + 1]
        box = [[(x_lo - c_n[i]) / h_n[i], (x_hi - c_n[i]) / h_n[i]]
               for i, (x_lo, x_hi) in enumerate(ends)]
        top = max(top, max(max(-x, y) for x, y in box))
    abs_e.append([max(-x, y) for x, y in box])
    return True, top, worst, worst_t, worst_i, "", np.array(abs_e)
