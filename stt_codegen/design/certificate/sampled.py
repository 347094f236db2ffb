"""Sampled-data check: the deployed, sampled law (13) keeps the plant in the tube.

Theorem 4.1 is a continuous-time result. The deployed controller reads ``x(t_k)`` at
``t_k = k dt``, computes ``u_k`` by law (13) with its clamps and holds it until
``t_{k+1}`` (zero-order hold). This module proves, for every plant of a plant class
(:class:`~stt_codegen.design.certificate.plant_class.PlantClass`: the spec's plant model and
``[assumptions]``), that ``|e_i| < 1`` at and between samples on the whole horizon of the
tube's certificate. The condition and its proof are in ``docs/sampled-data.md``. It
propagates, from ``e(0)``, an enclosure of ``e(t_k)`` that is the intersection of

* a box, one interval per axis (:mod:`.sampled_axis`: each axis on its own, the other
  inputs of its block of ``g`` taken at their worst through the coupling), and
* one Lyapunov ball per block of ``g`` (:mod:`.lyapunov`: ``sum atanh(e_i)^2 <= r^2``,
  the level of law (13)'s own function, in which the symmetric part of ``g`` enters as a
  matrix bound and its skew part cancels to first order).

Each part bounds the other: the box gives the ball its curvature, the ball caps the
other inputs in the box. On every interval ``x`` must stay strictly inside the
certified enclosure of the tube (:func:`~stt_codegen.design.certificate.enclose_tube`).
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from .enclosures import enclose_tube
from .refine import certify_tube
from ..gain import derived_gain
from ..samples import TubeSamples, sample_tube
from ...spec.assumptions import Assumptions
from ...spec.loader import Spec
from ...tube import reference
from ...tube.parameters import E_MAX, TubeDesign
from .lyapunov import level_after, next_level, others_max
from .plant_class import PlantClass, plant_class
from .predicted import check_predicted
from .sampled_fold import check_folded
from .sampled_axis import (axis_interval, clamp_failure, held_speed, peak, peak_for_box,
                           phi_scalar, start_box, phi_slope_scalar, room_failure, turn_failure,
                           turned_gains, unprovable)

__all__ = ["DELAY_HALVINGS", "KEPT_CHECKS", "RATE_FACTORS", "SampledCheck", "cached_check",
           "check_sampled", "check_sampled_first_per_axis", "delay_room", "largest_delay",
           "largest_passing", "lowest_rate", "sampled_check_of", "worst_near"]

#: Sampling-rate multiples tried by :func:`lowest_rate`, in increasing order.
RATE_FACTORS = (0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 2.0, 2.5, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0)
#: Iterations of the bootstrap of a ball's between-samples level (see :func:`_ball`).
BALL_ITERATIONS = 12


@dataclass(frozen=True)
class SampledCheck:
    """Outcome of :func:`check_sampled`.

    Attributes
    ----------
    passed : bool
        The sufficient condition holds: no plant of the class leaves the tube.
    level : float
        The proved bound of ``max_i |e_i(t_k)|`` at the samples; when failed, the bound
        reached before the failure.
    margin : float
        Smallest relative room left, ``min`` over intervals and dimensions of the room to
        the tube's edge between samples divided by the tube's half-width; negative when
        failed.
    time : float
        Start of the sampling interval where the margin is smallest, seconds.
    dimension : int
        Dimension (0-based) where the margin is smallest.
    reason : str
        Empty when passed, else what fails, in numbers.
    data : dict
        Numbers for reports.
    abs_e : ndarray or None, shape (K + 1, n)
        When passed: the proved bound of ``|e_i(t_k)|`` at every sample of ``samples``
        (read by :func:`stt_codegen.design.certificate.actuator.sampled_error_bound` for the input
        bound); when stopped (:func:`check_sampled`'s ``stop``), those up to the sample it
        stopped at; ``None`` otherwise.
    e_box : ndarray or None, shape (K + 1, n, 2)
        When passed: the proved interval ``[lo, hi]`` of the signed ``e_i(t_k)`` at every
        sample (``abs_e`` is ``max(-lo, hi)``), from which the sign of law (13)'s command
        is known where it excludes 0 (:mod:`stt_codegen.design.heading`); ``None``
        otherwise, and for the predicted law's check.
    """

    passed: bool
    level: float
    margin: float
    time: float
    dimension: int
    reason: str
    data: dict = field(default_factory=dict)
    abs_e: np.ndarray | None = field(default=None, compare=False, repr=False)
    e_box: np.ndarray | None = field(default=None, compare=False, repr=False)


def _atanh_reach(lo: float, hi: float) -> float:
    """``max |atanh e|`` over ``e`` in ``[lo, hi]`` (``inf`` if it reaches ``|e| >= 1``)."""
    top = max(-lo, hi)
    return math.atanh(top) if top < 1.0 else math.inf


def _within_ball(interval: list[float], edge: float) -> list[float]:
    """``interval`` (an enclosure of ``e_i``) cut to ``[-edge, edge]`` (the ball's bound of
    ``|e_i|``); ``interval`` uncut where the two miss each other.

    Both enclose ``e_i``, so they meet; they miss only by rounding (a ball's edge a few
    ulps below a box near ``e = 0``, where the box's corners come from state coordinates
    ``~1e-15`` apart). An empty cut would be an enclosure of nothing, which every later
    step would pass vacuously (and ``|e_i| <= -inf`` would reach ``phi'``): the box alone
    is kept.
    """
    low, high = max(interval[0], -edge), min(interval[1], edge)
    return [low, high] if low <= high else interval


def _as_class(plants: Assumptions | PlantClass) -> PlantClass:
    return plants if isinstance(plants, PlantClass) else PlantClass(plants)


def _ball(level: float, limits: list[float], halves: list[float], reach: list[float],
          gain: float, dt: float, g_min: float, g_max: float, skew: float,
          push: float) -> tuple[float, float]:
    """``(R_mid, R_end)`` of one block's ball on one interval, or ``(inf, inf)``.

    ``W <= R_mid^2`` on the whole interval and ``W <= R_end^2`` at its end, in this
    sample's coordinates. The curvature along the step needs a bound of ``|e_i|`` along
    it: the per-axis path range ``reach`` and a guessed level ``R``; the guess holds when
    the level it gives is strictly below it (a first-exit argument, docs/sampled-data.md).
    """
    guess = level * (1.0 + 1e-3) + 1e-6
    for _ in range(BALL_ITERATIONS):
        top = math.tanh(guess)
        if top > E_MAX:
            break
        rho = [min(r, top) for r in reach]
        curvature = [phi_slope_scalar(x) / h ** 2 for x, h in zip(rho, halves)]
        end_sq = level_after(level, limits, halves, curvature, gain, dt, g_min, g_max,
                             skew, push)
        if not math.isfinite(end_sq):
            break
        mid = math.sqrt(max(level * level, end_sq))
        if mid < guess:
            return mid, math.sqrt(max(end_sq, 0.0))
        guess = mid + 0.5 * (mid - level) + 1e-9
    return math.inf, math.inf


def worst_near(values: np.ndarray, jitter: float, pick) -> np.ndarray:
    """``values[k]`` per interval (rows: ``values[k, :]``), or with sampling jitter the
    worst (``pick``: ``np.minimum`` or ``np.maximum``) of intervals ``k - 1 .. k + 1``: a
    measurement interval ``[s_k, s_{k+1}]`` lies within ``[t_k - jitter, t_{k+1} +
    jitter]``.

    Parameters
    ----------
    values : ndarray, shape (K,) or (K, n)
        A bound per sampling interval.
    jitter : float
        ``[controller] jitter``, s; 0 returns ``values`` itself.
    pick : numpy ufunc
        ``np.minimum`` for a lower bound of a least value, ``np.maximum`` otherwise.

    Returns
    -------
    ndarray
        The shape of ``values``.
    """
    if not jitter > 0.0:
        return values
    before = np.concatenate([values[:1], values[:-1]])
    after = np.concatenate([values[1:], values[-1:]])
    return pick(pick(before, values), after)


def check_sampled(design: TubeDesign, samples: TubeSamples,
                  plants: Assumptions | PlantClass, gain: float | None = None, *,
                  lyapunov: bool = True, delay: float = 0.0,
                  jitter: float = 0.0,
                  stop: Callable[[int, list[float]], bool] | None = None,
                  folded: bool = True,
                  initial_error: Sequence[tuple[float, float]] | None = None
                  ) -> SampledCheck:
    """Prove that the sampled closed loop keeps ``|e_i| < 1`` at and between samples.

    A sufficient condition, checked by propagating an enclosure of ``e(t_k)`` (a box and
    one Lyapunov ball per block of ``g``) from ``e(0)`` (``docs/sampled-data.md``): on
    every sampling interval, for every plant ``x_dot = f(x) + g(x) u + w`` of the class and
    every ``e(t_k)`` in the enclosure, ``x`` stays strictly inside the tube's certified
    enclosure until ``t_{k+1}``, and ``e(t_{k+1})`` lies in the next enclosure, inside
    ``[-E_MAX, E_MAX]``.

    Parameters
    ----------
    design : TubeDesign
        Gives ``rate_hz``, ``x(0)`` and, unless ``gain`` is given, ``k`` of law (13).
    samples : TubeSamples
        The deployed tube at the rate of ``design``
        (:func:`~stt_codegen.design.samples.sample_tube`).
    plants : Assumptions or PlantClass
        The plant bounds (:func:`~stt_codegen.design.certificate.plant_class.plant_class` for a spec,
        which evaluates its plant model on the tube); ``input_gain[0] > 0`` is needed.
    gain : float, optional
        ``k`` to check instead of ``design.gain``.
    lyapunov : bool
        Use the Lyapunov balls (default); ``False`` keeps the per-axis argument alone,
        without the Lyapunov level (for comparisons). With a delay or jitter the balls are
        not used (their level assumes the interval's own command from its start).
    delay : float
        Largest computation delay, s (``[controller] delay``): the command computed from
        the state read at ``s_k`` acts from ``s_k + lag``, ``lag`` in ``[0, delay]`` (any,
        varying from sample to sample); before, the previous one acts (zero before the
        first).
    jitter : float
        Sampling jitter, s (``[controller] jitter``): ``|s_k - k dt| <= jitter``, ``s_0 =
        0``; the controller is called with the nominal ``t = k dt``. ``delay + 2 jitter``
        must not exceed ``dt``.
    stop : callable, optional
        ``(k, bound of |e_i(t_k)| per dimension) -> bool``, asked at every sample once its
        bound is proved: where it answers true the check ends there, not passed, with
        ``data["stopped_at"] = t_k`` and the bounds of samples ``0 .. k`` in ``abs_e`` (a
        caller that needs only whether a bound derived from ``|e|`` holds, such as the
        input bound's verdict, stops at the first sample that breaks it). The bounds up to
        ``k`` are those of the whole check.
    folded : bool
        Where no ball takes part, run the per-sample step folded into CasADi's virtual
        machine (:mod:`.sampled_fold`; the default: the same result, float for float, in a
        fraction of the time); ``False`` runs the Python loop, the fold's oracle.
    initial_error : sequence of (float, float), optional
        An interval ``[lo_i, hi_i]`` of ``e_i(0)`` per dimension (inside ``(-1, 1)``) from
        which the check starts, in place of the point ``e(x(0))``: a tube that takes over
        from another at a sample where the state is known only within such a box
        (docs/sensing.md, "The switch").

    Returns
    -------
    SampledCheck
        The verdict, its level and margin, the time and dimension of a failure, and the
        bounds of ``|e|``.

    Raises
    ------
    ValueError
        ``delay`` or ``jitter`` negative, or ``delay + 2 jitter > dt``; an
        ``initial_error`` not of ``n`` intervals inside ``(-1, 1)``.
    """
    cls = _as_class(plants)
    a = cls.assumptions
    k_gain = design.gain if gain is None else float(gain)
    n = design.dimension
    dt = 1.0 / design.rate_hz
    blocks = a.coupled_blocks(n)
    block_of = {i: b for b in blocks for i in b}
    if delay < 0.0 or jitter < 0.0 or delay + 2.0 * jitter > dt * (1.0 + 1e-12):
        raise ValueError(f"delay = {delay!r} s and jitter = {jitter!r} s must be >= 0 with "
                         f"delay + 2 jitter <= dt = {dt!r} s")
    timed = delay > 0.0 or jitter > 0.0
    # A measurement interval [s_k, s_{k+1}] lasts L in [dt - 2 jitter, dt + 2 jitter]; the
    # previous command acts for its first `lag` in [0, delay], this one for the rest, a
    # `share` (L - lag) / dt of a period. The bounds are affine in (L, lag) at each e(s_k),
    # so the four corners cover every L and every delay up to `delay`.
    corners = sorted({(max(0.0, (length - lag) / dt), lag)
                      for length in (dt - 2.0 * jitter, dt + 2.0 * jitter)
                      for lag in (0.0, delay)}) if timed else [(1.0, 0.0)]
    shares = sorted({share for share, _ in corners})
    balls = [b for b in blocks if len(b) > 1] if lyapunov and not timed else []
    lo, hi = samples.gamma_lower, samples.gamma_upper
    width = hi - lo
    data = {"gain": k_gain, "rate_hz": design.rate_hz, "delay": delay, "jitter": jitter,
            "input_gain": list(a.input_gain),
            "input_gain_skew": a.input_gain_skew,
            "input_gain_coupling": a.input_gain_coupling, "drift_bound": a.drift_bound,
            "disturbance_bound": a.disturbance_bound, "blocks": [list(b) for b in blocks]}

    def fail(reason: str, margin: float, t: float, i: int, level: float) -> SampledCheck:
        return SampledCheck(False, level, margin, t, i, reason, data)

    reason = unprovable(a.input_gain[0], float(width.min()))
    if reason is not None:
        return fail(reason, -math.inf, 0.0, 0, math.nan)
    enclosure = enclose_tube(design, samples)
    count = len(enclosure.t_start)
    bounds = cls.on_intervals(enclosure, count)
    data["refined_on_the_tube"] = list(bounds.refined)
    half = 0.5 * width
    centre = 0.5 * (hi + lo)
    pull = 4.0 * dt * k_gain / width                      # (K+1, n): dt |u| / phi per unit g
    g_min_a = worst_near(bounds.g_min, jitter, np.minimum)
    turn = a.input_gain_turn                              # (per |u|, constant) or None
    ratio = half[:count] / (pull[:count] * g_min_a[:, None])
    # the tube's inner edges over the measurement interval, in state units (with jitter the
    # worst of the neighbouring intervals), then in interval k's coordinates
    upper_min = worst_near(enclosure.upper_min, jitter, np.minimum)
    lower_max = worst_near(enclosure.lower_max, jitter, np.maximum)
    up_e_a = (upper_min - centre[:count]) / half[:count]
    low_e_a = (lower_max - centre[:count]) / half[:count]
    first_box = start_box(((np.array(design.initial_state) - centre[0]) / half[0]).tolist(),
                          initial_error)
    # the longest a command may act for (a base's turn over it)
    span = (dt + 2.0 * jitter) + (delay if timed else 0.0)
    if folded and not balls:
        # the per-axis argument: the folded loop (the same doubles)
        peaks_a = {share: (np.zeros_like(ratio) if turn is not None else
                           peak(ratio / share) if share > 0.0 else
                           np.full_like(ratio, 1.0 - 1e-15)) for share in shares}
        figures = {"centre": centre[:count], "half": half[:count], "pull": pull[:count],
                   "peak": peaks_a, "up_e": up_e_a, "low_e": low_e_a,
                   "centre_next": centre[1:count + 1], "half_next": half[1:count + 1],
                   "g_min": g_min_a, **{name: worst_near(getattr(bounds, name), jitter,
                                                         np.maximum)
                                        for name in ("g_max", "skew", "coupling", "push")}}
        found = check_folded(n, tuple(tuple(b) for b in blocks), turn, first_box,
                             samples.t[:count],
                             dt, k_gain, figures, stop, delay, span,
                             tuple(corners) if timed else None)
        if found[0] == "fail":
            return fail(*found[1:])
        if found[0] == "stopped":
            _, top, worst, t, i, t_stop, abs_e = found
            data["stopped_at"] = t_stop
            return SampledCheck(False, top, worst, t, i, f"stopped at t = {t:.4f} s", data,
                                abs_e)
        _, top, worst, worst_t, worst_i, abs_e, e_box = found
        data.update({"max_abs_e": top, "margin": worst, "max_level": 0.0,
                     "intervals_without_ball": 0})
        return SampledCheck(True, top, worst, worst_t, worst_i, "", data, abs_e, e_box)
    g_min_l = g_min_a.tolist()
    # s* of each share of the period the own command acts (a share of 0: no pull, s* = 1-)
    peaks = {share: peak(ratio / share).tolist() if share > 0.0 else
             np.full_like(ratio, 1.0 - 1e-15).tolist() for share in shares}
    up_e, low_e = up_e_a.tolist(), low_e_a.tolist()
    alpha = (half[:count] / half[1:count + 1]).tolist()
    beta = ((centre[:count] - centre[1:count + 1]) / half[1:count + 1]).tolist()
    half_l, centre_l, pull_l = half.tolist(), centre.tolist(), pull.tolist()
    g_max_l = worst_near(bounds.g_max, jitter, np.maximum).tolist()
    skew_l, coupling_l, push_l = (worst_near(v, jitter, np.maximum).tolist() for v in
                                  (bounds.skew, bounds.coupling, bounds.push))
    reach_prev = None                                     # |e(s_{k-1})| bound: no command yet
    speeds: list[float] = []                              # bound of |u_k| per sample
    box = [list(v) for v in first_box]                    # enclosure of e(t_k), per dim
    level = {b: math.sqrt(sum(max(abs(math.atanh(v)) for v in box[i]) ** 2 for i in b))
             for b in balls}
    worst, worst_t, worst_i = math.inf, 0.0, 0
    top = max(max(-x, y) for x, y in box)
    ball_lost = ball_max = 0.0
    abs_e = []                                            # the bound of |e(t_k)|, per sample
    boxes = []                                            # the enclosure of e(t_k), per sample
    for k in range(count):
        t = float(samples.t[k])
        reach_e = [max(-x, y) for x, y in box]
        abs_e.append(reach_e)
        boxes.append([list(v) for v in box])
        if max(reach_e) > E_MAX:
            i = int(np.argmax(reach_e))
            return fail(clamp_failure(i, max(reach_e), t), -math.inf, t, i, top)
        if stop is not None and stop(k, reach_e):
            data["stopped_at"] = t
            return SampledCheck(False, top, worst, t, int(np.argmax(reach_e)),
                                f"stopped at t = {t:.4f} s", data, np.array(abs_e))
        limits = [math.atanh(v) for v in reach_e]         # max |atanh e_i| over the box
        for b in balls:                                   # the box's corner bounds W too
            level[b] = min(level[b], math.sqrt(sum(limits[i] ** 2 for i in b)))
            ball_max = max(ball_max, level[b])
        h_k = half_l[k]
        g_lo, g_hi, sk, cp = g_min_l[k], g_max_l[k], skew_l[k], coupling_l[k]
        peak_k = {share: peaks[share][k] for share in shares}
        if turn is not None:
            # g turns with the heading the held command turns the base by (eq. (R1))
            speeds.append(math.sqrt(sum((pull_l[k][i] / dt * phi_scalar(reach_e[i])) ** 2
                                        for i in range(n))))
            rate = turn[0] * max(speeds[-3:] if timed else speeds[-1:]) + turn[1]
            g_lo, g_hi, sk, cp = turned_gains(span * rate, g_lo, g_hi, sk, cp)
            if g_lo <= 0.0:
                return fail(turn_failure(span * rate, rate, t), -math.inf, t, 0, top)
            ratio_k = [h_k[i] / (pull_l[k][i] * g_lo) for i in range(n)]
            # s* clipped to the ranges of |e_i| as peak_scalar's, bisected only where needed
            peak_k = {share: [peak_for_box(r / share, *box[i]) if share > 0.0
                              else 1.0 - 1e-15 for i, r in enumerate(ratio_k)]
                      for share in shares}
        path, ends = [], []
        for i in range(n):
            others = [j for j in block_of[i] if j != i]
            z_sq = (others_max([limits[j] for j in others], level.get(block_of[i], math.inf),
                               [h_k[j] for j in others]) if others else 0.0)
            if not timed:
                p_lo, p_hi, x_lo, x_hi = axis_interval(
                    box[i][0], box[i][1], centre_l[k][i], h_k[i], pull_l[k][i], g_lo,
                    g_hi, peak_k[1.0][i], dt * push_l[k],
                    dt * 2.0 * k_gain * math.sqrt(z_sq), cp, sk)
            else:
                # the previous command for `lag`, then this one for `share` periods
                # (docs/sampled-data.md, "Computation delay and jitter")
                speed = held_speed(i, block_of[i], reach_prev,
                                   [p / dt for p in pull_l[max(k - 1, 0)]], g_hi,
                                   g_hi - g_lo, sk, cp, push_l[k])
                p_lo = x_lo = math.inf
                p_hi = x_hi = -math.inf
                for share, lag in corners:
                    a_lo, a_hi, b_lo, b_hi = axis_interval(
                        box[i][0], box[i][1], centre_l[k][i], h_k[i], share * pull_l[k][i],
                        g_lo, g_hi, peak_k[share][i],
                        share * dt * push_l[k] + lag * speed,
                        share * dt * 2.0 * k_gain * math.sqrt(z_sq), cp, sk)
                    p_lo, p_hi = min(p_lo, a_lo), max(p_hi, a_hi)
                    x_lo, x_hi = min(x_lo, b_lo), max(x_hi, b_hi)
                # while the previous command acts, x moves from x(s_k) by at most this
                old = delay * speed
                p_lo = min(p_lo, centre_l[k][i] + box[i][0] * h_k[i] - old)
                p_hi = max(p_hi, centre_l[k][i] + box[i][1] * h_k[i] + old)
            path.append([(p_lo - centre_l[k][i]) / h_k[i], (p_hi - centre_l[k][i]) / h_k[i]])
            ends.append((x_lo, x_hi))
        reach_prev = reach_e
        end_level = {}
        for b in balls:
            mid, end = _ball(level[b], [limits[i] for i in b], [h_k[i] for i in b],
                             [min(max(-path[i][0], path[i][1]), 1.0) for i in b], k_gain, dt,
                             g_lo, g_hi, sk, push_l[k])
            if math.isfinite(mid):
                edge = math.tanh(mid)
                for i in b:
                    path[i] = _within_ball(path[i], edge)
            else:
                ball_lost += 1
            end_level[b] = end
        for i in range(n):
            room = min(up_e[k][i] - path[i][1], path[i][0] - low_e[k][i])
            if room < worst:
                worst, worst_t, worst_i = room, t, i
            if room <= 0.0:
                return fail(room_failure(i, t, dt, room), room, t, i, top)
        h_n, c_n = half_l[k + 1], centre_l[k + 1]
        # |atanh e_i(t_{k+1})| in this sample's coordinates, from the per-axis end ranges
        end_limits = [_atanh_reach((x_lo - centre_l[k][i]) / h_k[i],
                                   (x_hi - centre_l[k][i]) / h_k[i])
                      for i, (x_lo, x_hi) in enumerate(ends)]
        box = [[(x_lo - c_n[i]) / h_n[i], (x_hi - c_n[i]) / h_n[i]]
               for i, (x_lo, x_hi) in enumerate(ends)]
        for b in balls:
            r = (next_level(end_level[b], [alpha[k][i] for i in b], [beta[k][i] for i in b],
                            [end_limits[i] for i in b])
                 if math.isfinite(end_level[b]) else math.inf)
            level[b] = r
            if math.isfinite(r):
                edge = math.tanh(r)
                for i in b:
                    box[i] = _within_ball(box[i], edge)
        top = max(top, max(max(-x, y) for x, y in box))
    data.update({"max_abs_e": top, "margin": worst, "max_level": ball_max,
                 "intervals_without_ball": int(ball_lost)})
    abs_e.append([max(-x, y) for x, y in box])
    boxes.append([list(v) for v in box])
    return SampledCheck(True, top, worst, worst_t, worst_i, "", data, np.array(abs_e),
                        np.array(boxes))


def check_sampled_first_per_axis(design: TubeDesign, samples: TubeSamples,
                                 plants: Assumptions | PlantClass,
                                 gain: float | None = None, *, delay: float = 0.0,
                                 jitter: float = 0.0, compensate: bool = False,
                                 stop: Callable[[int, list[float]], bool] | None = None,
                                 initial_error: Sequence[tuple[float, float]] | None = None
                                 ) -> SampledCheck:
    """:func:`check_sampled` with the per-axis argument alone, and with the Lyapunov balls
    only where that fails; with ``compensate`` and a delay, the check of the predicted law
    (:func:`~.predicted.check_predicted`).

    The balls only cut the per-axis enclosures (every step intersects with them), so a pass
    of the per-axis argument is a pass of the whole check: the verdict is the whole
    check's, at the cost of the per-axis argument wherever it suffices (the balls cost
    about four times as much). When the per-axis argument passes, its bounds are the ones
    reported, which the balls could only have tightened.

    Parameters
    ----------
    design : TubeDesign
        As :func:`check_sampled`.
    samples : TubeSamples
        As :func:`check_sampled`.
    plants : Assumptions or PlantClass
        As :func:`check_sampled`.
    gain : float, optional
        As :func:`check_sampled`.
    delay, jitter : float
        As :func:`check_sampled` (with either, the per-axis argument is the whole check).
    compensate : bool
        ``[controller] compensate_delay``: law (13) at the state predicted over ``delay``
        (up to ``dt``; ``jitter`` must be 0). With ``delay`` 0 the prediction is the state
        itself and the check is the plain one.
    stop : callable, optional
        :func:`check_sampled`'s ``stop``, asked by the per-axis argument and, where that
        fails, by the whole check (not with ``compensate``): a check it stops is returned
        as stopped.
    initial_error : sequence of (float, float), optional
        As :func:`check_sampled` (with ``compensate`` too).

    Returns
    -------
    SampledCheck
        The per-axis argument's when it passes (or stops), else the whole check's.

    Raises
    ------
    ValueError
        As :func:`check_sampled`; with ``compensate``, a ``jitter`` other than 0 or a
        ``delay`` beyond ``dt``.
    """
    if compensate and delay > 0.0:
        if jitter != 0.0:
            raise ValueError(f"jitter = {jitter!r} s: the predicted law is proved without "
                             "jitter")
        passed, level, margin, t, i, reason, abs_e = check_predicted(
            design, samples, _as_class(plants), gain, delay=delay,
            initial_error=initial_error)
        data = {"gain": design.gain if gain is None else float(gain),
                "rate_hz": design.rate_hz, "delay": delay, "jitter": 0.0,
                "compensate_delay": True, "max_abs_e": level, "margin": margin}
        return SampledCheck(passed, level, margin, t, i, reason, data, abs_e)
    per_axis = check_sampled(design, samples, plants, gain, lyapunov=False, delay=delay,
                             jitter=jitter, stop=stop, initial_error=initial_error)
    if per_axis.passed or delay > 0.0 or jitter > 0.0 or "stopped_at" in per_axis.data:
        return per_axis
    return check_sampled(design, samples, plants, gain, stop=stop,
                         initial_error=initial_error)


#: Halvings of the bisection of :func:`largest_delay` (a resolution of ``dt / 2^6``).
DELAY_HALVINGS = 6


def largest_delay(design: TubeDesign, spec: Spec) -> float | None:
    """The largest computation delay the sampled-data check proves at the design's rate and
    gain with the spec's jitter, to ``dt / 2^DELAY_HALVINGS`` below the true limit of the
    check (docs/sampled-data.md, "Computation delay and jitter"); with ``[controller]
    compensate_delay``, of the predicted law, up to one period.

    Parameters
    ----------
    design : TubeDesign
        The design (its rate and gain).
    spec : Spec
        Its plant class and ``[controller] jitter`` and ``compensate_delay``.

    Returns
    -------
    float or None
        Seconds, in ``[0, dt - 2 jitter]`` (``[0, dt]`` with ``compensate_delay``): the largest delay tried with which the check
        passes; a check with a delay proves every delay up to it. ``None`` when the check
        fails without delay.
    """
    with reference.numpy_math():
        samples = sample_tube(design)
        plants = plant_class(spec)

        def passes(delay: float) -> bool:
            return check_sampled_first_per_axis(design, samples, plants, delay=delay,
                                                jitter=spec.jitter,
                                                compensate=spec.compensate_delay).passed

        # without delay: the spec's own check when it has no delay either (cached)
        return largest_passing(passes, delay_room(design.rate_hz, spec),
                               sampled_check_of(design, spec)[1].passed if spec.delay == 0.0
                               else None)


def delay_room(rate_hz: float, spec: Spec) -> float:
    """The largest delay the sampled-data check takes at a rate, s: ``dt - 2 jitter``, or
    ``dt`` with ``[controller] compensate_delay``.

    Parameters
    ----------
    rate_hz : float
        The rate, Hz.
    spec : Spec
        Its ``jitter`` and ``compensate_delay``.

    Returns
    -------
    float
        Seconds, ``>= 0``.
    """
    return max(0.0, 1.0 / rate_hz - (0.0 if spec.compensate_delay else 2.0 * spec.jitter))


def largest_passing(passes: Callable[[float], bool], top: float,
                    zero_passes: bool | None = None, halvings: int = DELAY_HALVINGS
                    ) -> float | None:
    """The largest delay in ``[0, top]`` that ``passes`` accepts, by bisection to
    ``top / 2^halvings``: the largest one tried that passes.

    Parameters
    ----------
    passes : callable
        ``passes(delay) -> bool``, a certificate with that delay.
    top : float
        The largest delay allowed, s.
    zero_passes : bool, optional
        ``passes(0.0)`` when it is known (a cached check); else it is asked.
    halvings : int
        Halvings of the bisection.

    Returns
    -------
    float or None
        Seconds; ``None`` when the delay 0 fails.
    """
    if not (passes(0.0) if zero_passes is None else zero_passes):
        return None
    if passes(top):
        return top
    good, bad = 0.0, top
    for _ in range(halvings):
        mid = 0.5 * (good + bad)
        good, bad = (mid, bad) if passes(mid) else (good, mid)
    return good


def sampled_check_of(design: TubeDesign, spec: Spec, per_axis_first: bool = True,
                     stop_for: Callable[[TubeSamples], Callable[[int, list[float]], bool]]
                     | None = None,
                     initial_error: tuple[tuple[float, float], ...] | None = None
                     ) -> tuple[TubeSamples, SampledCheck]:
    """The sampled-data check of a designed tube for its spec's plant class, once per
    process: the design's tracking proof, the ``[actuator]`` proof and ``verify`` ask for
    the same check of the same tube (a bundled design is asked for again and again).

    The tube is sampled with numpy's ufuncs for the oracle's exp/log/tanh (within an ulp
    of libm, as the certificate does: every margin here is far above rounding), over the
    default horizon of :func:`~stt_codegen.design.samples.sample_tube`. A process keeps its
    last :data:`KEPT_CHECKS` whole checks (:func:`cached_check`); a check stopped early is
    not kept.

    Parameters
    ----------
    design : TubeDesign
        With its gain.
    spec : Spec
        Its plant class (:func:`~stt_codegen.design.certificate.plant_class.plant_class`).
    per_axis_first : bool
        :func:`check_sampled_first_per_axis` (the same verdict; where the per-axis argument
        passes, its bounds, which the Lyapunov balls could only tighten) instead of
        :func:`check_sampled` with the balls everywhere.
    stop_for : callable, optional
        ``samples -> stop``: :func:`check_sampled`'s ``stop`` for the tube's samples, for a
        caller that needs a verdict only (the input bound's); used where no whole check
        is kept (which is read instead) and not with ``[controller] compensate_delay``.
        With ``per_axis_first``, the per-axis argument stops there (its bounds, looser
        than the balls', may break a limit theirs keep).
    initial_error : tuple of (float, float), optional
        :func:`check_sampled`'s ``initial_error``: the check from a box of ``e(0)``.

    Returns
    -------
    samples : TubeSamples
        The design's tube at its sampling instants.
    check : SampledCheck
        The verdict (``data["stopped_at"]`` when ``stop`` ended it).
    """
    key = (design, spec, bool(per_axis_first), initial_error)
    found = cached_check(*key)
    if found is not None:
        return found
    with reference.numpy_math():
        samples = sample_tube(design)
        plants = plant_class(spec)
        timing = {"delay": spec.delay, "jitter": spec.jitter}
        stop = None if stop_for is None or spec.compensate_delay else stop_for(samples)
        if per_axis_first or spec.compensate_delay:
            check = check_sampled_first_per_axis(design, samples, plants, **timing,
                                                 compensate=spec.compensate_delay, stop=stop,
                                                 initial_error=initial_error)
        else:
            check = check_sampled(design, samples, plants, **timing, stop=stop,
                                  initial_error=initial_error)
    if "stopped_at" in check.data:
        return samples, check
    _KEPT[key] = (samples, check)
    while len(_KEPT) > KEPT_CHECKS:
        _KEPT.popitem(last=False)
    return samples, check


#: The whole checks :func:`sampled_check_of` keeps, the latest last (at most
#: :data:`KEPT_CHECKS`).
_KEPT: OrderedDict[tuple, tuple[TubeSamples, SampledCheck]] = OrderedDict()
#: How many whole checks a process keeps.
KEPT_CHECKS = 16


def cached_check(design: TubeDesign, spec: Spec, per_axis_first: bool,
                 initial_error: tuple[tuple[float, float], ...] | None = None
                 ) -> tuple[TubeSamples, SampledCheck] | None:
    """The whole check :func:`sampled_check_of` keeps for these arguments, or ``None``
    (nothing computed, or only a check stopped early)."""
    key = (design, spec, per_axis_first, initial_error)
    found = _KEPT.get(key)
    if found is not None:
        _KEPT.move_to_end(key)
    return found


def lowest_rate(design: TubeDesign, spec: Spec, plants: Assumptions | PlantClass,
                explicit_gain: float | None = None,
                passes_at_rate: bool | None = None) -> tuple[float | None, float | None]:
    """The lowest of ``rate_hz`` times :data:`RATE_FACTORS` at which the design holds.

    At each rate the tube keeps its circumvents and segments, is certified again
    (:func:`~stt_codegen.design.certificate.certify_tube`: the deployed ``alpha`` and the
    sampling-rate check depend on the rate), and the sampled check
    (:func:`check_sampled`) must pass with the gain the design would use there:
    ``explicit_gain`` if given, else :func:`~stt_codegen.design.gain.derived_gain` at that
    rate's certified narrowest width. When the design holds at ``rate_hz`` the factors
    below 1 are tried in increasing order; else the largest factor first (if it fails, no
    factor is reported), then the others above 1 in increasing order.

    Parameters
    ----------
    design : TubeDesign
        The design: its tube, ``rate_hz`` and gain.
    spec : Spec
        For the certificate (state space, obstacles, target).
    plants : Assumptions or PlantClass
        The plant bounds the sampled check uses.
    explicit_gain : float, optional
        The gain ``k`` of law (13) at every rate (the spec's ``controller.gain``); default the
        gain derived at each rate.
    passes_at_rate : bool, optional
        Whether the check already passed at ``design.rate_hz`` with its gain (saves a run);
        default: find out.

    Returns
    -------
    rate_hz, gain : float or None
        The lowest rate found, Hz, and the gain used there; ``(None, None)`` when no factor
        tried works.
    """
    assumptions = _as_class(plants).assumptions

    def passes(factor: float) -> tuple[bool, float]:
        trial = replace(design, rate_hz=design.rate_hz * factor)
        certificate = certify_tube(trial, spec)
        gain = (explicit_gain if explicit_gain is not None
                else derived_gain(certificate.min_width, trial.rate_hz, assumptions))
        if not certificate.passed or spec.delay > delay_room(trial.rate_hz, spec):
            return False, gain         # the delay (s) and jitter must fit the shorter period
        return check_sampled_first_per_axis(trial, sample_tube(trial), plants, gain,
                                            delay=spec.delay, jitter=spec.jitter,
                                            compensate=spec.compensate_delay).passed, gain

    below = [f for f in RATE_FACTORS if f < 1.0]
    above = [f for f in RATE_FACTORS if f > 1.0]
    if passes_at_rate is None:
        passes_at_rate, gain_at_rate = passes(1.0)
    else:
        gain_at_rate = (explicit_gain if explicit_gain is not None
                        else derived_gain(certify_tube(design, spec).min_width,
                                          design.rate_hz, assumptions))
    if passes_at_rate:
        for factor in below:
            ok, gain = passes(factor)
            if ok:
                return design.rate_hz * factor, gain
        return design.rate_hz, gain_at_rate
    # the fastest rate first: when even it fails, one check answers instead of all of them
    ok, fastest_gain = passes(above[-1])
    if not ok:
        return None, None
    for factor in above[:-1]:
        ok, gain = passes(factor)
        if ok:
            return design.rate_hz * factor, gain
    return design.rate_hz * above[-1], fastest_gain
