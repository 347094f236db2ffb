"""Law (13)'s per-axis sampled check, its per-sample step folded into a compiled loop.

:func:`~.sampled.check_sampled` propagates an enclosure of ``e(t_k)`` from sample to
sample. Where no Lyapunov ball takes part (every block of ``g`` a single axis, or
``lyapunov=False``: the per-axis argument) and the loop has no computation delay or
jitter, one step is a box of ``e`` per axis in and out: :func:`axis_step` writes it once on
CasADi ``SX`` symbols with the formulas the loop calls (:func:`~.sampled_axis.axis_interval`,
:func:`~.lyapunov.others_box`, :func:`~.sampled_axis.turned_gains`,
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
from .folded import StepLayout, run_steps, split
from .lyapunov import others_box
from .operations import SYMBOLS, exact_symbols
from .sampled_axis import axis_interval, peak_scalar, phi_scalar, turn_failure, turned_gains

__all__ = ["AXIS_COLUMNS", "AXIS_FIGURES", "AXIS_PARAMETERS", "axis_step", "check_folded"]

#: The tube's figures of one step, ``n`` rows each (``peak``: ``s*`` of the sample, unused
#: by a turning base's step), then the class's bounds on the interval, one row each.
AXIS_COLUMNS = ("centre", "half", "pull", "peak", "up_e", "low_e", "centre_next",
                "half_next", "g_min", "g_max", "skew", "coupling", "push")
#: The constants: the period, the factor ``2 dt k`` of the other inputs' pull, and a
#: turning base's ``|omega| <= turn_per |u| + turn_const`` and the span it turns over.
AXIS_PARAMETERS = ("dt", "pull_others", "turn_per", "turn_const", "span")
#: What a step returns per axis: the bound of ``|e_i(t_k)|``, the room to the tube's edge
#: on the interval (half-widths), and (the same on every axis) the least input gain over
#: the turn and the bound of ``|omega|`` (a base's; ``g_min`` and 0 otherwise).
AXIS_FIGURES = ("reach", "room", "gain", "rate")
_SCALARS = ("g_min", "g_max", "skew", "coupling", "push")


def _layouts(n: int) -> tuple[StepLayout, StepLayout]:
    return (StepLayout((name, 1 if name in _SCALARS else n) for name in AXIS_COLUMNS),
            StepLayout((name, 1) for name in AXIS_PARAMETERS))


@lru_cache(maxsize=16)
def axis_step(n: int, blocks: tuple[tuple[int, ...], ...], turn: bool
              ) -> tuple[casadi.Function, StepLayout, StepLayout]:
    """One step of the per-axis check as a CasADi function ``(state, column, constants) ->
    (next state, figures)``.

    ``state`` is the box of ``e(t_k)``: its lower ends, then its upper ends (``2 n`` rows);
    ``figures`` are :data:`AXIS_FIGURES` (``4 n`` rows).

    Parameters
    ----------
    n : int
        Axes.
    blocks : tuple of tuple of int
        The blocks of ``g`` (``Assumptions.coupled_blocks``).
    turn : bool
        A differential drive's gains, turned by the held command (``input_gain_turn``).

    Returns
    -------
    step : casadi.Function
    columns, constants : StepLayout
        The rows of ``column`` (:data:`AXIS_COLUMNS`) and ``constants``
        (:data:`AXIS_PARAMETERS`).
    """
    ops, fmin, fmax = SYMBOLS, SYMBOLS.fmin, SYMBOLS.fmax
    block_of = {i: b for b in blocks for i in b}
    columns, constants = _layouts(n)
    with exact_symbols():
        state = casadi.SX.sym("state", 2 * n)
        col = casadi.SX.sym("column", columns.size)
        par = casadi.SX.sym("constants", constants.size)
        c = {name: split(col, columns, name) for name in AXIS_COLUMNS}
        dt, pull_others, turn_per, turn_const, span = (split(par, constants, name)[0]
                                                       for name in AXIS_PARAMETERS)
        g_lo, g_hi, sk, cp, push = (c[name][0] for name in _SCALARS)
        lo = [state[i] for i in range(n)]
        hi = [state[n + i] for i in range(n)]
        reach = [fmax(-lo[i], hi[i]) for i in range(n)]
        limits = [ops.atanh(v) for v in reach]
        h_k, pull = c["half"], c["pull"]
        peak_k = c["peak"]
        rate = casadi.SX(0.0)
        if turn:
            # as the loop: the speed the command may ask, the turn it causes, the gains
            speed = ops.sqrt(sum((pull[i] / dt * phi_scalar(reach[i], ops)) ** 2
                                 for i in range(n)))
            rate = turn_per * speed + turn_const
            g_lo, g_hi, sk, cp = turned_gains(span * rate, g_lo, g_hi, sk, cp, ops)
            peak_k = [peak_scalar(h_k[i] / (pull[i] * g_lo) / 1.0, ops) for i in range(n)]
        after_lo, after_hi, rooms = [], [], []
        for i in range(n):
            others = [j for j in block_of[i] if j != i]
            z_sq = (others_box([limits[j] for j in others], [h_k[j] for j in others], ops)
                    if others else 0.0)
            p_lo, p_hi, x_lo, x_hi = axis_interval(
                lo[i], hi[i], c["centre"][i], h_k[i], pull[i], g_lo, g_hi, peak_k[i],
                dt * push, pull_others * ops.sqrt(z_sq), cp, sk, ops=ops)
            path_lo = (p_lo - c["centre"][i]) / h_k[i]
            path_hi = (p_hi - c["centre"][i]) / h_k[i]
            rooms.append(fmin(c["up_e"][i] - path_hi, path_lo - c["low_e"][i]))
            after_lo.append((x_lo - c["centre_next"][i]) / c["half_next"][i])
            after_hi.append((x_hi - c["centre_next"][i]) / c["half_next"][i])
        shown = casadi.vertcat(*reach, *rooms, *([g_lo] * n), *([rate] * n))
        step = casadi.Function("axis_sampled_step", [state, col, par],
                               casadi.cse([casadi.vertcat(*after_lo, *after_hi), shown]))
    return step, columns, constants


def check_folded(n: int, blocks: tuple[tuple[int, ...], ...], turn: tuple[float, float] | None,
                 e0: list[float], times: np.ndarray, dt: float, gain: float,
                 figures: dict[str, np.ndarray],
                 stop: Callable[[int, list[float]], bool] | None):
    """The per-axis check over the samples: :func:`~.sampled.check_sampled`'s loop without
    balls, delay or jitter, folded.

    Parameters
    ----------
    n : int
        Axes.
    blocks : tuple of tuple of int
        The blocks of ``g``.
    turn : (float, float) or None
        ``input_gain_turn``: ``|omega| <= turn[0] |u| + turn[1]`` (a base), or ``None``.
    e0 : list of float
        ``e(0)``.
    times : ndarray, (K,)
        The samples' times, s (``K`` intervals).
    dt : float
        The period, s.
    gain : float
        ``k`` of law (13).
    figures : dict of str to ndarray
        The columns of :data:`AXIS_COLUMNS`, ``(K, n)`` (the class's bounds ``(K,)``).
    stop : callable or None
        :func:`~.sampled.check_sampled`'s ``stop``.

    Returns
    -------
    tuple
        ``("fail", reason, margin, t, i, level)``, ``("stopped", level, margin, t, i,
        t_stop, abs_e)``, or ``("passed", level, margin, t, i, abs_e)``, as the loop
        returns them.
    """
    step, columns, constants = axis_step(n, blocks, turn is not None)
    count = len(times)
    values = {"dt": dt, "pull_others": dt * 2.0 * gain,
              "turn_per": turn[0] if turn else 0.0, "turn_const": turn[1] if turn else 0.0,
              "span": (dt + 2.0 * 0.0) + 0.0}
    table = columns.pack({name: np.asarray(figures[name], dtype=float).T
                          for name in AXIS_COLUMNS}, count)
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

    start = np.concatenate([np.asarray(e0, dtype=float)] * 2)
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
            return ("fail", f"|e_{i}| may reach {reach[k].max():.6g} at t = {t:.4f} s, beyond "
                            f"the clamp E_MAX", -math.inf, t, i, top)
        if turn is not None and shown[2][0][k] <= 0.0:
            rate = float(shown[3][0][k])
            return ("fail", turn_failure(values["span"] * rate, rate, t), -math.inf, t, 0, top)
        i = int(np.flatnonzero(room[k] <= 0.0)[0])
        return ("fail", f"a plant of the class may leave the tube in dimension {i} on "
                        f"[{t:.4f}, {t + dt:.4f}] s (the enclosure of x reaches "
                        f"{-float(room[k][i]):.3g} half-widths beyond its edge)",
                float(room[k][i]), t, i, top)
    final = np.maximum(-last[:n], last[n:])
    worst, worst_t, worst_i = worst_before(count)
    top = max(float(tops[-1]), float(final.max()))
    return ("passed", top, worst, worst_t, worst_i, np.vstack([reach, final[None, :]]))
