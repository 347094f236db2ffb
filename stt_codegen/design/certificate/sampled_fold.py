"""Law (13)'s per-axis sampled check, its per-sample step folded into a compiled loop.

:func:`~.sampled.check_sampled` propagates an enclosure of ``e(t_k)`` from sample to
sample. Where no Lyapunov ball takes part (every block of ``g`` a single axis,
``lyapunov=False``: the per-axis argument, or a computation delay or jitter, with which
the balls are not used) one step is a box of ``e`` per axis in and out (with a delay or
jitter also the bound of ``|e|`` at the sample before and a base's last speeds):
:func:`axis_step` writes it once on CasADi ``SX`` symbols with the formulas the loop calls
(:func:`~.sampled_axis.axis_interval`, :func:`~.lyapunov.others_box`,
:func:`~.sampled_axis.turned_gains`, :func:`~.sampled_axis.held_speed`,
:func:`~.sampled_axis.peak_scalar`; the same IEEE operations in the same order) and
:func:`check_folded` runs it over the samples (:func:`~.folded.run_steps`) and judges its
figures in the loop's order, so its verdict, margins, bounds and words are the loop's
(docs/sampled-data.md, "How the check is evaluated"; ``tests/test_sampled_fold.py``
compares them float for float).

The tube's figures a step needs (centre, half-width, pull, the inner edges of the
certified enclosure, the class's bounds on the interval, the peaks ``s*``) are computed
beforehand for all samples with numpy, as the loop does, and passed one column per step
(:data:`AXIS_COLUMNS`). A differential drive's gains turn with the heading the held
command turns the base by, which depends on the bound of ``|e|`` at the sample: its step
computes the turn and ``s*`` itself (a bisection on every sample, where the loop bisects
only where the box's range of ``|e|`` does not decide it: the same values after the
clipping :func:`~.sampled_axis.axis_interval` applies).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import lru_cache

import casadi
import numpy as np

from ...tube.parameters import E_MAX
from .folded import StepLayout, StepSymbols, run_steps
from .lyapunov import others_box
from .operations import SYMBOLS, exact_symbols
from .sampled_axis import (axis_interval, clamp_failure, held_speed, peak_scalar, phi_scalar,
                           room_failure, turn_failure, turned_gains)

__all__ = ["AXIS_COLUMNS", "AXIS_FIGURES", "AXIS_PARAMETERS", "axis_step", "check_folded"]

#: The tube's figures of one step, ``n`` rows each (``peak``: ``s*`` of the sample per
#: share of a period the own command acts, unused by a turning base's step; ``pull_prev``:
#: the previous sample's pull), then the class's bounds on the interval and ``first`` (1 at
#: the first sample: no command acts before it), one row each.
AXIS_COLUMNS = ("centre", "half", "pull", "pull_prev", "peak", "up_e", "low_e",
                "centre_next", "half_next", "g_min", "g_max", "skew", "coupling", "push",
                "first")
#: The constants: the period, a turning base's ``|omega| <= turn_per |u| + turn_const`` and
#: the span it turns over, the delay, ``k``, the shares of a period the own command acts
#: (sorted), and per corner of the interval's length and lag its share and lag.
AXIS_PARAMETERS = ("dt", "turn_per", "turn_const", "span", "delay", "gain", "shares", "share",
                   "lag")
#: What a step returns per axis: the bound of ``|e_i(t_k)|``, the room to the tube's edge
#: on the interval (half-widths), (the same on every axis) the least input gain over the
#: turn and the bound of ``|omega|`` (a base's; ``g_min`` and 0 otherwise), and the box of
#: the signed ``e_i(t_k)`` (its lower and upper ends).
AXIS_FIGURES = ("reach", "room", "gain", "rate", "lower", "upper")
_SCALARS = ("g_min", "g_max", "skew", "coupling", "push", "first")


def _layouts(n: int, shares: int, corners: int) -> tuple[StepLayout, StepLayout]:
    sizes = {"peak": shares * n, **{name: 1 for name in _SCALARS}}
    counts = {"shares": shares, "share": corners, "lag": corners}
    return (StepLayout((name, sizes.get(name, n)) for name in AXIS_COLUMNS),
            StepLayout((name, counts.get(name, 1)) for name in AXIS_PARAMETERS))


def _structure(corners: tuple[tuple[float, float], ...]) -> tuple[tuple[bool, ...],
                                                                  tuple[int, ...]]:
    """What a step's operations depend on in the corners: per share of a period (sorted)
    whether it is positive, and per corner the index of its share (the values are
    constants of the step)."""
    shares = sorted({share for share, _ in corners})
    return (tuple(share > 0.0 for share in shares),
            tuple(shares.index(share) for share, _ in corners))


def axis_step(n: int, blocks: tuple[tuple[int, ...], ...], turn: bool,
              corners: tuple[tuple[float, float], ...] | None = None
              ) -> tuple[casadi.Function, StepLayout, StepLayout]:
    """One step of the per-axis check as a CasADi function ``(state, column, constants) ->
    (next state, figures)``.

    ``state`` is the box of ``e(t_k)`` (its lower ends, then its upper ends), then the bound
    of ``|e(t_{k-1})|`` and of the two speeds a base's commands asked before (``5 n``
    rows; the last ``3 n`` serve a delay or jitter); ``figures`` are :data:`AXIS_FIGURES`
    (``6 n`` rows).

    Parameters
    ----------
    n : int
        Axes.
    blocks : tuple of tuple of int
        The blocks of ``g`` (``Assumptions.coupled_blocks``).
    turn : bool
        A differential drive's gains, turned by the held command (``input_gain_turn``).
    corners : tuple of (float, float), optional
        With a delay or jitter, the corners ``(share, lag)`` of the interval's length and
        lag, as :func:`~.sampled.check_sampled` sorts them; ``None`` without.

    Returns
    -------
    step : casadi.Function
    columns, constants : StepLayout
        The rows of ``column`` (:data:`AXIS_COLUMNS`) and ``constants``
        (:data:`AXIS_PARAMETERS`).
    """
    return _step(n, blocks, turn, None if corners is None else _structure(corners))


@lru_cache(maxsize=16)
def _step(n: int, blocks: tuple[tuple[int, ...], ...], turn: bool,
          structure: tuple[tuple[bool, ...], tuple[int, ...]] | None
          ) -> tuple[casadi.Function, StepLayout, StepLayout]:
    """:func:`axis_step` for the corners' :func:`_structure` (``None``: no delay)."""
    ops, fmin, fmax = SYMBOLS, SYMBOLS.fmin, SYMBOLS.fmax
    block_of = {i: b for b in blocks for i in b}
    timed = structure is not None
    positive, share_of = structure if timed else ((True,), (0,))
    columns, constants = _layouts(n, len(positive), len(share_of))
    with exact_symbols():
        symbols = StepSymbols(5 * n, columns, constants)
        state, c, p = symbols.state, symbols.c, symbols.p
        dt, turn_per, turn_const, span, delay, gain = (p[name][0]
                                                        for name in AXIS_PARAMETERS[:6])
        g_lo, g_hi, sk, cp, push, first = (c[name][0] for name in _SCALARS)
        lo, hi, reach_prev, speed_1, speed_2 = ([state[j * n + i] for i in range(n)]
                                                for j in range(5))
        reach = [fmax(-lo[i], hi[i]) for i in range(n)]
        limits = [ops.atanh(v) for v in reach]
        h_k, pull = c["half"], c["pull"]
        peak_k = [c["peak"][j * n:(j + 1) * n] for j in range(len(positive))]
        rate = speed = casadi.SX(0.0)
        if turn:
            # as the loop: the speed the command may ask, the turn it causes, the gains
            speed = ops.sqrt(sum((pull[i] / dt * phi_scalar(reach[i], ops)) ** 2
                                 for i in range(n)))
            fastest = fmax(fmax(speed_2[0], speed_1[0]), speed) if timed else speed
            rate = turn_per * fastest + turn_const
            g_lo, g_hi, sk, cp = turned_gains(span * rate, g_lo, g_hi, sk, cp, ops)
            ratio = [h_k[i] / (pull[i] * g_lo) for i in range(n)]
            peak_k = [[peak_scalar(r / p["shares"][j], ops) if positive[j] else 1.0 - 1e-15
                       for r in ratio] for j in range(len(positive))]
        after_lo, after_hi, rooms = [], [], []
        for i in range(n):
            others = [j for j in block_of[i] if j != i]
            z_sq = (others_box([limits[j] for j in others], [h_k[j] for j in others], ops)
                    if others else 0.0)
            centre = c["centre"][i]
            if not timed:
                p_lo, p_hi, x_lo, x_hi = axis_interval(
                    lo[i], hi[i], centre, h_k[i], pull[i], g_lo, g_hi, peak_k[0][i],
                    dt * push, dt * 2.0 * gain * ops.sqrt(z_sq), cp, sk, ops=ops)
            else:
                # the previous command for `lag`, then this one for `share` periods
                held = held_speed(i, block_of[i], reach_prev,
                                  [q / dt for q in c["pull_prev"]], g_hi, g_hi - g_lo, sk,
                                  cp, push, ops)
                held = ops.select(first > 0.5, push, held)
                p_lo = x_lo = math.inf
                p_hi = x_hi = -math.inf
                for j, which in enumerate(share_of):
                    a_lo, a_hi, b_lo, b_hi = axis_interval(
                        lo[i], hi[i], centre, h_k[i], p["share"][j] * pull[i], g_lo, g_hi,
                        peak_k[which][i], p["share"][j] * dt * push + p["lag"][j] * held,
                        p["share"][j] * dt * 2.0 * gain * ops.sqrt(z_sq), cp, sk, ops=ops)
                    p_lo, p_hi = fmin(p_lo, a_lo), fmax(p_hi, a_hi)
                    x_lo, x_hi = fmin(x_lo, b_lo), fmax(x_hi, b_hi)
                # while the previous command acts, x moves from x(s_k) by at most this
                old = delay * held
                p_lo = fmin(p_lo, centre + lo[i] * h_k[i] - old)
                p_hi = fmax(p_hi, centre + hi[i] * h_k[i] + old)
            path_lo = (p_lo - centre) / h_k[i]
            path_hi = (p_hi - centre) / h_k[i]
            rooms.append(fmin(c["up_e"][i] - path_hi, path_lo - c["low_e"][i]))
            after_lo.append((x_lo - c["centre_next"][i]) / c["half_next"][i])
            after_hi.append((x_hi - c["centre_next"][i]) / c["half_next"][i])
        following = casadi.vertcat(*after_lo, *after_hi, *reach, *([speed] * n),
                                   *([speed_1[0]] * n))
        shown = casadi.vertcat(*reach, *rooms, *([g_lo] * n), *([rate] * n), *lo, *hi)
        step = symbols.function("axis_sampled_step", following, shown)
    return step, columns, constants


def check_folded(n: int, blocks: tuple[tuple[int, ...], ...], turn: tuple[float, float] | None,
                 start_box: list[list[float]], times: np.ndarray, dt: float, gain: float,
                 figures: dict[str, np.ndarray],
                 stop: Callable[[int, list[float]], bool] | None,
                 delay: float = 0.0, span: float | None = None,
                 corners: tuple[tuple[float, float], ...] | None = None):
    """The per-axis check over the samples: :func:`~.sampled.check_sampled`'s loop without
    balls, folded.

    Parameters
    ----------
    n : int
        Axes.
    blocks : tuple of tuple of int
        The blocks of ``g``.
    turn : (float, float) or None
        ``input_gain_turn``: ``|omega| <= turn[0] |u| + turn[1]`` (a base), or ``None``.
    start_box : list of [float, float]
        The enclosure of ``e(0)``, one interval per axis.
    times : ndarray, (K,)
        The samples' times, s (``K`` intervals).
    dt : float
        The period, s.
    gain : float
        ``k`` of law (13).
    figures : dict of str to ndarray
        The columns of :data:`AXIS_COLUMNS` but ``pull_prev`` and ``first``, ``(K, n)``
        (the class's bounds ``(K,)``, with a jitter the worst of the neighbouring
        intervals; ``peak``: a dict of ``(K, n)`` per share of a period).
    stop : callable or None
        :func:`~.sampled.check_sampled`'s ``stop``.
    delay : float
        The computation delay, s.
    span : float, optional
        The longest a command acts, s (a base turns over it; default ``dt``).
    corners : tuple of (float, float), optional
        With either, the corners ``(share, lag)`` (:func:`axis_step`).

    Returns
    -------
    tuple
        ``("fail", reason, margin, t, i, level)``, ``("stopped", level, margin, t, i,
        t_stop, abs_e)``, or ``("passed", level, margin, t, i, abs_e, e_box)``, as the
        loop returns them (``e_box``: ``(K + 1, n, 2)``, the signed box of each
        ``e(t_k)``).
    """
    step, columns, constants = axis_step(n, blocks, turn is not None, corners)
    count = len(times)
    shares = sorted({share for share, _ in corners}) if corners else [1.0]
    values = {"dt": dt,
              "turn_per": turn[0] if turn else 0.0, "turn_const": turn[1] if turn else 0.0,
              "span": dt if span is None else span, "delay": delay,
              "gain": gain, "shares": shares,
              "share": [share for share, _ in corners] if corners else [1.0],
              "lag": [lag for _, lag in corners] if corners else [0.0]}
    pull = np.asarray(figures["pull"], dtype=float)
    rows = {name: np.asarray(figures[name], dtype=float).T for name in AXIS_COLUMNS
            if name not in ("peak", "pull_prev", "first")}
    rows["pull_prev"] = np.vstack([pull[:1], pull[:-1]]).T
    rows["peak"] = np.vstack([np.asarray(figures["peak"][share], dtype=float).T
                              for share in shares])
    rows["first"] = (np.arange(count) == 0).astype(float)
    table = columns.pack(rows, count)
    judged = {"done": 0, "stop": None, "fail": None}

    def failed(chunk: np.ndarray) -> bool:
        first = judged["done"]
        judged["done"] += chunk.shape[2]
        reach, room, low = chunk[0].T, chunk[1].T, chunk[2][0]
        bad = (reach.max(axis=1) > E_MAX) | (room <= 0.0).any(axis=1)
        if turn is not None:
            bad |= low <= 0.0
        hits = np.flatnonzero(bad)
        end = int(hits[0]) + 1 if hits.size else chunk.shape[2]
        if stop is not None:
            for j, row in enumerate(reach[:end].tolist()):
                if max(row) > E_MAX:
                    break
                if stop(first + j, row):
                    judged["stop"] = first + j
                    return True
        if hits.size:
            judged["fail"] = first + int(hits[0])
            return True
        return False

    start = np.concatenate([np.array([lo for lo, _ in start_box], dtype=float),
                            np.array([hi for _, hi in start_box], dtype=float)]
                           + [np.zeros(n), np.full(2 * n, -math.inf)])
    shown, last = run_steps(step, start, lambda a, b: table[:, a:b], count,
                            constants.pack(values), failed, kinds=len(AXIS_FIGURES))
    reach, room = shown[0].T, shown[1].T
    tops = np.maximum.accumulate(reach.max(axis=1))

    def worst_before(k: int) -> tuple[float, float, int]:
        if k == 0:
            return math.inf, 0.0, 0
        flat = int(np.argmin(room[:k]))
        return float(room[:k].flat[flat]), float(times[flat // n]), flat % n

    k = judged["stop"] if judged["stop"] is not None else judged["fail"]
    if k is not None:
        t, top = float(times[k]), float(tops[k])
        if judged["stop"] is not None:
            worst, _, _ = worst_before(k)
            return ("stopped", top, worst, t, int(np.argmax(reach[k])), t, reach[:k + 1])
        if reach[k].max() > E_MAX:
            i = int(np.argmax(reach[k]))
            return ("fail", clamp_failure(i, float(reach[k].max()), t), -math.inf, t, i, top)
        if turn is not None and shown[2][0][k] <= 0.0:
            rate = float(shown[3][0][k])
            return ("fail", turn_failure(values["span"] * rate, rate, t), -math.inf, t, 0, top)
        i = int(np.flatnonzero(room[k] <= 0.0)[0])
        return ("fail", room_failure(i, t, dt, float(room[k][i])), float(room[k][i]), t, i, top)
    final = np.maximum(-last[:n], last[n:2 * n])
    worst, worst_t, worst_i = worst_before(count)
    top = max(float(tops[-1]), float(final.max()))
    e_box = np.stack([np.vstack([shown[4].T, last[None, :n]]),
                      np.vstack([shown[5].T, last[None, n:2 * n]])], axis=2)
    return ("passed", top, worst, worst_t, worst_i, np.vstack([reach, final[None, :]]), e_box)
