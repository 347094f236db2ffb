"""The per-sample step of the sampled cascade's certificate, folded into a compiled loop.

:func:`~.cascade_sampled.check_cascade_sampled` and
:func:`~.cascade_sampled.check_cascade_predicted` propagate, sample after sample, a box of
``e1`` and one of ``e2`` per axis (and, with a computation delay, the previous input or
the prediction's miss): each step depends on the one before, so the loop is sequential.
This module writes one step once, with the per-axis formulas of
:func:`~.sampled_axis.axis_interval`, :func:`~.cascade_bounds.virtual_velocity_change` and
:func:`~.cascade_bounds.step_velocity_change` on CasADi ``SX`` symbols
(:data:`~.operations.SYMBOLS`, without simplifications: the same IEEE operations in the
same order as on floats), folds it with ``mapaccum`` and lets CasADi's virtual machine run
it over the samples (:mod:`.folded`; no C compiler; docs/second-order.md, "How the
certificate is evaluated").

Every figure a step needs from the tube (its centre, half-width and enclosures, the
velocity tube's half-width, the peaks ``s*``) is computed beforehand for all samples at
once with numpy and passed as one column per step (:data:`SAMPLED_COLUMNS`,
:data:`PREDICTED_COLUMNS`, ``n`` rows each). Each step returns the figures the check
judges (:data:`FIGURES`, ``n`` rows each); :func:`~.folded.run_steps` evaluates the steps
in chunks and stops after the first chunk in which a judgement fails, so a refusal costs
about as many steps as before.
"""

from __future__ import annotations

from functools import lru_cache

import casadi
import numpy as np

from .cascade_bounds import step_velocity_change, virtual_velocity_change
from .folded import StepLayout, StepSymbols
from .operations import SYMBOLS, exact_symbols
from .sampled_axis import axis_interval, peak_scalar, phi_scalar

__all__ = ["FIGURES", "PREDICTED_COLUMNS", "PREDICTED_PARAMETERS", "RHO_ROUNDING",
           "SAMPLED_COLUMNS", "SAMPLED_PARAMETERS", "predicted_step", "sampled_step"]

#: Relative safety factor on the closed-form ``rho2(t_{k+1})`` the path is judged against
#: (rounding of ``exp``; every margin reported is far above it).
RHO_ROUNDING = 1e-12

#: What a step returns per axis, in this order: the bounds of ``|e1|``, ``|e2|`` at the
#: sample (before the step), of ``|u_k|`` and of ``|x2|`` on the interval, the position
#: and velocity room, the bound of ``|e1|`` at the next sample, and the change of ``r``.
FIGURES = ("reach1", "reach2", "u_abs", "speed", "room", "vroom", "reach_next", "dr")

#: The tube's figures of one step of the plain (or timed) check, ``n`` rows each; ``peak1``
#: is repeated per share of a period the own force acts on the position stage, ``peak2``
#: per corner of the velocity stage; ``edge`` is the velocity tube's half-width the
#: interval is judged against.
SAMPLED_COLUMNS = ("centre", "half", "centre_next", "half_next", "pull1", "peak1", "up_e",
                   "low_e", "room_up", "room_low", "width_min", "width_max", "move", "rho",
                   "rho_next", "peak2", "edge")
#: The constants of the plain (or timed) check (``f0``, the drift bound per axis, and
#: ``vbound``: ``n`` of them, ``vbound`` ``inf`` when
#: none; ``share``: one per share; ``corner_share``, ``corner_lag``: one per corner;
#: ``length``: one per interval length).
SAMPLED_PARAMETERS = ("k1", "k2", "h", "g_min", "g_max", "coupling", "f0", "f1", "w",
                      "longest", "delay", "vbound", "share", "corner_share", "corner_lag",
                      "length")
#: The tube's figures of one step of the predicted check, ``n`` rows each (``_a``: over
#: the actuation interval; ``_r``: over ``[t_k, t_{k+1} + delay]``).
PREDICTED_COLUMNS = ("centre", "half", "centre_next", "half_next", "pull1", "peak1", "up_e",
                     "low_e", "room_up", "room_low", "width_max_a", "move_r", "width_min_r",
                     "width_max_r", "move", "width_min", "width_max", "rho", "rho_next",
                     "peak2", "late")
#: The constants of the predicted check (``f0`` and ``vbound``: ``n`` of them).
PREDICTED_PARAMETERS = ("k1", "k2", "h", "g_min", "g_max", "coupling", "f0", "f1", "w",
                        "delay", "deviation", "g_mid", "share", "mix_lo", "mix_hi", "vbound")

def _sampled_layouts(n: int, shares: int, corners: int, lengths: int
                     ) -> tuple[StepLayout, StepLayout]:
    sizes = {"peak1": shares * n, "peak2": corners * n}
    columns = StepLayout((name, sizes.get(name, n)) for name in SAMPLED_COLUMNS)
    sizes = {"f0": n, "vbound": n, "share": shares, "corner_share": corners,
             "corner_lag": corners, "length": lengths}
    return columns, StepLayout((name, sizes.get(name, 1)) for name in SAMPLED_PARAMETERS)


def _predicted_layouts(n: int) -> tuple[StepLayout, StepLayout]:
    return (StepLayout((name, n) for name in PREDICTED_COLUMNS),
            StepLayout((name, n if name in ("f0", "vbound") else 1)
                       for name in PREDICTED_PARAMETERS))


def _union(intervals, ops) -> tuple:
    """The union of :func:`~.sampled_axis.axis_interval`'s ``(path_lo, path_hi, end_lo,
    end_hi)`` over corners."""
    p_lo = x_lo = np.inf
    p_hi = x_hi = -np.inf
    for a_lo, a_hi, b_lo, b_hi in intervals:
        p_lo, p_hi = ops.fmin(p_lo, a_lo), ops.fmax(p_hi, a_hi)
        x_lo, x_hi = ops.fmin(x_lo, b_lo), ops.fmax(x_hi, b_hi)
    return p_lo, p_hi, x_lo, x_hi


@lru_cache(maxsize=16)
def sampled_step(n: int, timed: bool, delayed: bool, shares: int, corners: int,
                 lengths: int) -> tuple[casadi.Function, StepLayout, StepLayout]:
    """One step of :func:`~.cascade_sampled.check_cascade_sampled` as a CasADi function
    ``(state, column, constants) -> (next state, figures)``.

    ``state`` is ``(lower, upper)`` of the box of ``e1``, then of ``e2``, then the bound of
    the previous ``|u|`` (``5 n`` rows; the last ``n`` stay 0 without ``timed``);
    ``figures`` are :data:`FIGURES` (``8 n`` rows).

    Parameters
    ----------
    n : int
        Axes.
    timed : bool
        A computation delay or jitter (the corners of the interval's length and lag).
    delayed : bool
        A computation delay: the previous force acts at the start of an interval.
    shares, corners, lengths : int
        How many shares of a period the position stage takes, corners the velocity stage,
        and interval lengths the change of ``r`` at the next sample (1, 1, 1 untimed).

    Returns
    -------
    step : casadi.Function
    columns, constants : StepLayout
        The rows of ``column`` (:data:`SAMPLED_COLUMNS`) and ``constants``
        (:data:`SAMPLED_PARAMETERS`).
    """
    ops, fmin, fmax = SYMBOLS, SYMBOLS.fmin, SYMBOLS.fmax
    columns, constants = _sampled_layouts(n, shares, corners, lengths)
    with exact_symbols():
        symbols = StepSymbols(5 * n, columns, constants)
        state, c, p = symbols.state, symbols.c, symbols.p
        k1, k2, h, g_min, g_max, cpl, _, f1, w_amp, longest, delay = (
            p[name][0] for name in SAMPLED_PARAMETERS[:11])
        f0 = p["f0"]
        b1lo, b1hi, b2lo, b2hi, u_prev = (
            [state[j * n + i] for i in range(n)] for j in range(5))
        reach1 = [fmax(-b1lo[i], b1hi[i]) for i in range(n)]
        reach2 = [fmax(-b2lo[i], b2hi[i]) for i in range(n)]
        rho_k, rho_n = c["rho"], c["rho_next"]
        u_abs = [2.0 * k2 / rho_k[i] * phi_scalar(reach2[i], ops) for i in range(n)]
        u_sq = sum(v * v for v in u_abs)
        u_prev_sq = sum(v * v for v in u_prev)
        figures = {name: [] for name in FIGURES}
        after = [[], [], [], []]
        for i in range(n):
            others = ops.sqrt(fmax(u_sq - u_abs[i] ** 2, 0.0))
            z_abs = reach2[i] * rho_k[i]
            centre, half = c["centre"][i], c["half"][i]
            r_abs = 4.0 * k1 / (2.0 * half) * phi_scalar(reach1[i], ops)
            if not timed:
                push_free = g_max * u_abs[i] + cpl * others + f0[i] + w_amp  # w/o F1
                speed = (r_abs + z_abs + h * push_free) / (1.0 - h * f1)
            else:
                # the force is u_{k-1} for the lag, then u_k: x2 moves under the larger
                force_old = g_max * u_prev[i] + cpl * ops.sqrt(
                    fmax(u_prev_sq - u_prev[i] ** 2, 0.0)) if delayed else 0.0
                force = fmax(g_max * u_abs[i] + cpl * others, force_old)
                speed = ((r_abs + z_abs + longest * (force + f0[i] + w_amp))
                         / (1.0 - longest * f1))
            drift = f0[i] + f1 * speed + w_amp
            if not timed:
                accel = g_max * u_abs[i] + cpl * others + drift
                # position stage: law (13) with g = 1 and a displacement <= tau (Z + h A/2)
                shift = h * z_abs + 0.5 * h * h * accel
                p_lo, p_hi, x_lo, x_hi = axis_interval(
                    b1lo[i], b1hi[i], centre, half, c["pull1"][i], 1.0, 1.0, c["peak1"][i],
                    shift, ops=ops)
            else:
                accel = force + drift                     # the old force's and the new's
                shift = longest * z_abs + 0.5 * longest * longest * accel
                p_lo, p_hi, x_lo, x_hi = _union((axis_interval(
                    b1lo[i], b1hi[i], centre, half, share * c["pull1"][i], 1.0, 1.0,
                    c["peak1"][j * n + i], shift, ops=ops)
                    for j, share in enumerate(p["share"])), ops)
            e_lo = (p_lo - centre) / half
            e_hi = (p_hi - centre) / half
            room = fmin(c["up_e"][i] - e_hi, e_lo - c["low_e"][i])
            gap = fmin(c["room_up"][i] - p_hi, p_lo - c["room_low"][i])
            e1_path = fmax(1.0 - 2.0 * gap / c["width_max"][i], reach1[i])
            dr = virtual_velocity_change(k1, longest if timed else h, reach1[i], e1_path,
                                         speed, c["move"][i], c["width_min"][i],
                                         c["width_max"][i], ops)
            # velocity stage: law (13)'s transform on |z| < rho2, the change of r on top
            pull2 = 2.0 * h * k2 / rho_k[i]
            if not timed:
                q_lo, q_hi, z_lo, z_hi = axis_interval(
                    b2lo[i], b2hi[i], 0.0, rho_k[i], pull2, g_min, g_max, c["peak2"][i],
                    h * drift, h * others, cpl, 0.0, ops=ops)
            else:
                old = force_old + drift                   # |x2_dot| under u_{k-1}
                q_lo, q_hi, z_lo, z_hi = _union((axis_interval(
                    b2lo[i], b2hi[i], 0.0, rho_k[i], share * pull2, g_min, g_max,
                    c["peak2"][j * n + i], share * h * drift + lag * old,
                    share * h * others, cpl, 0.0, ops=ops)
                    for j, (share, lag) in enumerate(zip(p["corner_share"],
                                                         p["corner_lag"]))), ops)
                # while the previous force acts, z moves from z(s_k) by at most this
                q_lo = fmin(q_lo, b2lo[i] * rho_k[i] - delay * old)
                q_hi = fmax(q_hi, b2hi[i] * rho_k[i] + delay * old)
            edge = c["edge"][i] * (1.0 - RHO_ROUNDING)
            vroom = 1.0 - fmax(-(q_lo - dr), q_hi + dr) / edge
            centre_n, half_n = c["centre_next"][i], c["half_next"][i]
            box_lo, box_hi = (x_lo - centre_n) / half_n, (x_hi - centre_n) / half_n
            reach_n = fmax(fmax(-box_lo, box_hi), reach1[i])
            # at the next sample: over the interval's length, h without jitter (the bound
            # is convex in the length: its ends cover the range)
            change = None
            for length in (p["length"] if timed else [h]):
                bound = step_velocity_change(k1, length, b1lo[i], b1hi[i],
                                             (centre - centre_n) / half_n, half / half_n,
                                             reach_n, half, half_n, shift, ops)
                change = bound if change is None else fmax(change, bound)
            dr_end = fmin(dr, change)
            after[0].append(box_lo)
            after[1].append(box_hi)
            after[2].append((z_lo - dr_end) / rho_n[i])
            after[3].append((z_hi + dr_end) / rho_n[i])
            for name, value in zip(FIGURES, (reach1[i], reach2[i], u_abs[i], speed, room,
                                             vroom, reach_n, dr)):
                figures[name].append(value)
        following = casadi.vertcat(*after[0], *after[1], *after[2], *after[3],
                                   *(u_abs if timed else u_prev))
        shown = casadi.vertcat(*(v for name in FIGURES for v in figures[name]))
        # one node per distinct operation on the same operands (the same doubles)
        step = symbols.function("cascade_sampled_step", following, shown)
    return step, columns, constants


@lru_cache(maxsize=4)
def predicted_step(n: int) -> tuple[casadi.Function, StepLayout, StepLayout]:
    """One step of :func:`~.cascade_sampled.check_cascade_predicted` (the law at the state
    predicted over the delay) as a CasADi function ``(state, column, constants) -> (next
    state, figures)``.

    ``state`` is ``(lower, upper)`` of the box of the predicted ``e1``, then of ``e2``, then
    the prediction's misses in position and velocity (``6 n`` rows); ``figures`` are
    :data:`FIGURES` (``8 n`` rows).

    Parameters
    ----------
    n : int
        Axes.

    Returns
    -------
    step : casadi.Function
    columns, constants : StepLayout
        The rows of ``column`` (:data:`PREDICTED_COLUMNS`) and ``constants``
        (:data:`PREDICTED_PARAMETERS`).
    """
    ops, fmin, fmax = SYMBOLS, SYMBOLS.fmin, SYMBOLS.fmax
    columns, constants = _predicted_layouts(n)
    with exact_symbols():
        symbols = StepSymbols(6 * n, columns, constants)
        state, c, p = symbols.state, symbols.c, symbols.p
        (k1, k2, h, g_min, g_max, cpl, _, f1, w_amp, delay, deviation, g_mid, share,
         mix_lo, mix_hi) = (p[name][0] for name in PREDICTED_PARAMETERS[:15])
        f0 = p["f0"]
        b1lo, b1hi, b2lo, b2hi, eta1, eta2 = (
            [state[j * n + i] for i in range(n)] for j in range(6))
        reach1 = [fmax(-b1lo[i], b1hi[i]) for i in range(n)]
        reach2 = [fmax(-b2lo[i], b2hi[i]) for i in range(n)]
        rho_k, rho_n = c["rho"], c["rho_next"]
        u_abs = [2.0 * k2 / rho_k[i] * phi_scalar(reach2[i], ops) for i in range(n)]
        u_sq = sum(v * v for v in u_abs)
        figures = {name: [] for name in FIGURES}
        after = [[], [], [], [], [], []]
        for i in range(n):
            others = ops.sqrt(fmax(u_sq - u_abs[i] ** 2, 0.0))
            z_abs = reach2[i] * rho_k[i]
            centre, half = c["centre"][i], c["half"][i]
            r_abs = 4.0 * k1 / (2.0 * half) * phi_scalar(reach1[i], ops)
            force = g_max * u_abs[i] + cpl * others
            # (C2) |x2| on [a_k, a_{k+1}]: from x2_hat = r_k + z_hat, the miss, the interval
            speed = (r_abs + z_abs + eta2[i] + h * (force + f0[i] + w_amp)) / (1.0 - h * f1)
            drift = f0[i] + f1 * speed + w_amp
            # (C2) the position stage: law (13) with g = 1 at x1_hat, x1(a_k) = x1_hat + miss
            shift = h * (z_abs + eta2[i]) + 0.5 * h * h * (force + drift)
            p_lo, p_hi, x_lo, x_hi = axis_interval(
                b1lo[i], b1hi[i], centre, half, c["pull1"][i], 1.0, 1.0, c["peak1"][i],
                shift, ops=ops)
            p_lo, p_hi = p_lo - eta1[i], p_hi + eta1[i]
            room = fmin(c["up_e"][i] - (p_hi - centre) / half,
                        (p_lo - centre) / half - c["low_e"][i])
            gap = fmin(c["room_up"][i] - p_hi, p_lo - c["room_low"][i])
            e1_path = fmax(1.0 - 2.0 * gap / c["width_max_a"][i], reach1[i])
            # (C3) |r(x1(t), t) - r(x1_hat_k, t_k)| for t in [a_k, a_{k+1}]
            dr = virtual_velocity_change(k1, 1.0, reach1[i], e1_path, eta1[i] + h * speed,
                                         c["move_r"][i], c["width_min_r"][i],
                                         c["width_max_r"][i], ops)
            q_lo, q_hi, _, _ = axis_interval(
                b2lo[i], b2hi[i], 0.0, rho_k[i], 2.0 * h * k2 / rho_k[i], g_min, g_max,
                c["peak2"][i], h * drift, h * others, cpl, 0.0, ops=ops)
            spread = eta2[i] + dr
            vroom = 1.0 - fmax(-(q_lo - spread), q_hi + spread) / (c["late"][i]
                                                                    * (1.0 - RHO_ROUNDING))
            # (C4) the next prediction: from x_hat_k, the miss, the share of the period
            # from a_k to s_{k+1} under the class, and the rest at g_mid exactly
            shift_hat = (eta1[i] + h * (z_abs + eta2[i]) + 0.5 * (h * h - delay * delay)
                         * (force + drift) + 0.5 * delay * delay * g_mid * u_abs[i])
            _, _, xh_lo, xh_hi = axis_interval(
                b1lo[i], b1hi[i], centre, half, c["pull1"][i], 1.0, 1.0, c["peak1"][i],
                shift_hat, ops=ops)
            centre_n, half_n = c["centre_next"][i], c["half_next"][i]
            box_lo, box_hi = (xh_lo - centre_n) / half_n, (xh_hi - centre_n) / half_n
            reach_n = fmax(-box_lo, box_hi)
            pull2 = 2.0 * h * k2 / rho_k[i]
            _, _, zh_lo, zh_hi = axis_interval(
                b2lo[i], b2hi[i], 0.0, rho_k[i], pull2, mix_lo, mix_hi,
                peak_scalar(rho_k[i] / (mix_lo * pull2), ops), share * h * drift + eta2[i],
                h * others, share * cpl, 0.0, ops=ops)    # the other axes: share * g's rows
            # |r(x1_hat_{k+1}, t_{k+1}) - r(x1_hat_k, t_k)|: x1_hat moves by h r_k and at
            # most shift_hat beyond it
            dr_end = fmin(virtual_velocity_change(
                k1, 1.0, reach1[i], fmax(reach1[i], reach_n), h * r_abs + shift_hat,
                c["move"][i], c["width_min"][i], c["width_max"][i], ops), step_velocity_change(
                k1, h, b1lo[i], b1hi[i], (centre - centre_n) / half_n, half / half_n,
                fmax(reach1[i], reach_n), half, half_n, shift_hat, ops))
            # the miss of that prediction, which u_k makes over [s_{k+1}, a_{k+1}] (C1)
            miss = deviation * u_abs[i] + cpl * others + drift
            for j, value in enumerate((box_lo, box_hi, (zh_lo - dr_end) / rho_n[i],
                                       (zh_hi + dr_end) / rho_n[i], 0.5 * delay * delay * miss,
                                       delay * miss)):
                after[j].append(value)
            for name, value in zip(FIGURES, (reach1[i], reach2[i], u_abs[i], speed, room,
                                             vroom, reach_n, dr)):
                figures[name].append(value)
        following = casadi.vertcat(*(v for block in after for v in block))
        shown = casadi.vertcat(*(v for name in FIGURES for v in figures[name]))
        step = symbols.function("cascade_predicted_step", following, shown)
    return step, columns, constants
