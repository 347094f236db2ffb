"""The sampled cascade's certificate as it was written before its per-sample step was
compiled (stt-codegen 6fb655a, stt_codegen/design/certificate/cascade_sampled.py and
sampled_axis.py): a plain-float Python loop, kept here only as the test oracle of
:func:`stt_codegen.design.certificate.cascade_sampled.check_cascade_sampled` and
:func:`~stt_codegen.design.certificate.cascade_sampled.check_cascade_predicted`
(tests/test_cascade_compiled.py compares them float for float). Not part of the package."""

# flake8: noqa
from __future__ import annotations

import math

import numpy as np

from stt_codegen.design.certificate.cascade_sampled import CascadeCheck, CascadeClass
from stt_codegen.design.certificate.enclosures import enclose_later, enclose_tube
from stt_codegen.design.certificate.sampled import worst_near
from stt_codegen.design.certificate.sampled_axis import peak
from stt_codegen.design.samples import TubeSamples
from stt_codegen.progress import report
from stt_codegen.tube.parameters import E_MAX, GAMMA_D_MIN, TubeDesign
from stt_codegen.tube.second_stage import SecondStage

RHO_ROUNDING = 1e-12
PROGRESS_REPORTS = 50
STEP_PIECES = 8


def phi_scalar(s: float) -> float:
    """:func:`phi` for one float.

    Parameters
    ----------
    s : float
        ``|e_i|`` in ``[0, 1)``.

    Returns
    -------
    float
        ``phi(s)``.
    """
    return 2.0 * math.atanh(s) / (1.0 - s * s)


def phi_slope_scalar(s: float) -> float:
    """:func:`phi_slope` for one float.

    Parameters
    ----------
    s : float
        ``e_i`` in ``(-1, 1)``.

    Returns
    -------
    float
        ``phi'(s)``; ``inf`` for ``|s| >= 1`` (its limit at the tube's edge, as
        :func:`phi_slope` gives at ``+-1``: a curvature bound that holds nowhere, so an
        argument using it fails rather than passes).
    """
    if not abs(s) < 1.0:
        return math.inf
    return (2.0 + 4.0 * s * math.atanh(s)) / (1.0 - s * s) ** 2


def peak_scalar(ratio: float) -> float:
    """:func:`peak` for one float.

    Parameters
    ----------
    ratio : float
        ``h / (g_min p)``.

    Returns
    -------
    float
        ``s*`` in ``[0, 1)``.
    """
    if not ratio > 2.0:
        return 0.0
    lo, hi = 0.0, 1.0 - 1e-15
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if phi_slope_scalar(mid) < ratio:
            lo = mid
        else:
            hi = mid
    return lo


def coupling_push(others: float, coupling: float, spread: float, skew: float,
                  own: float) -> float:
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

    Returns
    -------
    float
        The bound, state units: the least of ``coupling others`` and the symmetric bound plus
        ``skew others``; 0 when ``others <= 0``.
    """
    if others <= 0.0:
        return 0.0
    if others <= 2.0 * own:
        symmetric = spread * others * others / (4.0 * own)
    else:
        symmetric = spread * (others - own)
    return min(coupling * others, symmetric + skew * others)


def axis_interval(a: float, b: float, c0: float, h0: float, pull: float, g_min: float,
                  g_max: float, s_peak: float, push: float, others: float = 0.0,
                  coupling: float = 0.0, skew: float = 0.0) -> tuple[float, float, float, float]:
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

    Returns
    -------
    path_lo, path_hi, end_lo, end_hi : float
        ``x_i`` on the whole interval, and at ``t_{k+1}``, state units.
    """
    spread = g_max - g_min
    path_lo = end_lo = math.inf
    path_hi = end_hi = -math.inf
    for sign, s_a, s_b in ((1.0, max(a, 0.0), b), (-1.0, max(-b, 0.0), -a)):
        if s_b < s_a or (s_b == 0.0 and sign < 0):
            continue
        phi_a, phi_b = phi_scalar(s_a), phi_scalar(s_b)
        extra = push + coupling_push(others, coupling, spread, skew, pull * phi_a)
        start_a, start_b = sign * c0 + s_a * h0, sign * c0 + s_b * h0
        s_star = min(max(s_peak, s_a), s_b)
        phi_star = phi_a if s_star == s_a else phi_b if s_star == s_b else phi_scalar(s_star)
        out_max = sign * c0 + s_star * h0 - pull * g_min * phi_star + extra
        in_min = min(start_a - pull * g_max * phi_a, start_b - pull * g_max * phi_b) - extra
        low, high = min(start_a, in_min), max(start_b, out_max)
        if sign > 0:
            path_lo, path_hi = min(path_lo, low), max(path_hi, high)
            end_lo, end_hi = min(end_lo, in_min), max(end_hi, out_max)
        else:
            path_lo, path_hi = min(path_lo, -high), max(path_hi, -low)
            end_lo, end_hi = min(end_lo, -out_max), max(end_hi, -in_min)
    return path_lo, path_hi, end_lo, end_hi


def virtual_velocity_change(k1: float, h: float, e1_start: float, e1_path: float,
                            speed: float, tube_move: float, width_min: float,
                            width_max: float) -> float:
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

    Returns
    -------
    float
        Velocity units.
    """
    de1 = (2.0 * h * speed + (1.0 + e1_start) * tube_move) / width_min
    return 4.0 * k1 * (phi_slope_scalar(e1_path) * de1 / width_min
                       + phi_scalar(e1_start) * (1.0 / width_min - 1.0 / width_max))


#: Pieces the range of ``e1(t_k)`` is cut into for :func:`step_velocity_change`.
STEP_PIECES = 8


def step_velocity_change(k1: float, h: float, a: float, b: float, shift: float,
                         scale: float, reach: float, half_k: float, half_n: float,
                         other: float) -> float:
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

    Returns
    -------
    float
        Velocity units.
    """
    pull = 2.0 * k1 * h / half_k
    h_ratio = 1.0 / half_n
    worst = 0.0
    edges = [a + (b - a) * j / STEP_PIECES for j in range(STEP_PIECES + 1)]
    # phi at each edge once (phi is odd: phi(|e|) = |phi(e)|); the same values as per piece
    phis = [phi_scalar(e) for e in edges]
    stretch = 1.0 / half_n - 1.0 / half_k
    widen = abs(stretch)
    slope_k, other_n, tilt = 2.0 * k1 / half_n, other * h_ratio, scale - 1.0
    for j in range(STEP_PIECES):
        c, d = edges[j], edges[j + 1]
        lin_c, lin_d = tilt * c, tilt * d
        m_hi = (lin_c if lin_c > lin_d else lin_d) + shift + h_ratio * (-pull * phis[j])
        m_lo = (lin_d if lin_c > lin_d else lin_c) + shift + h_ratio * (-pull * phis[j + 1])
        move = max(abs(m_hi), abs(m_lo)) + other_n
        wide = abs(c) if abs(c) >= abs(d) else abs(d)
        phi_wide = abs(phis[j]) if abs(c) >= abs(d) else abs(phis[j + 1])
        top = min(wide + move, reach)
        apart = slope_k * phi_slope_scalar(top) * move + 2.0 * k1 * phi_wide * widen
        far = wide + move
        if far >= 1.0:
            worst = max(worst, apart)
            continue
        # phi(e + m) / h_n - phi(e) / h_k = phi'(xi) m / h_n + phi(e) (1 / h_n - 1 / h_k)
        p_lo, p_hi = c + min(m_lo, 0.0), d + max(m_hi, 0.0)
        steepest = phi_slope_scalar(far)
        flattest = phi_slope_scalar(0.0 if p_lo * p_hi <= 0.0 else min(abs(p_lo), abs(p_hi)))
        turned_lo = h_ratio * min(flattest * m_lo, steepest * m_lo) + min(
            phis[j] * stretch, phis[j + 1] * stretch)
        turned_hi = h_ratio * max(flattest * m_hi, steepest * m_hi) + max(
            phis[j] * stretch, phis[j + 1] * stretch)
        together = 2.0 * k1 * (max(abs(turned_lo), abs(turned_hi))
                               + steepest * other_n * h_ratio)
        worst = max(worst, min(apart, together))
    return worst


def _union(intervals) -> tuple[float, float, float, float]:
    """The union of :func:`~.sampled_axis.axis_interval`'s ``(path_lo, path_hi, end_lo,
    end_hi)`` over corners."""
    p_lo = x_lo = math.inf
    p_hi = x_hi = -math.inf
    for a_lo, a_hi, b_lo, b_hi in intervals:
        p_lo, p_hi = min(p_lo, a_lo), max(p_hi, a_hi)
        x_lo, x_hi = min(x_lo, b_lo), max(x_hi, b_hi)
    return p_lo, p_hi, x_lo, x_hi


class _Tally:
    """The running figures of one cascade check (least margins and where, largest errors
    at the samples, peak input and velocity per axis) and its :class:`CascadeCheck`."""

    def __init__(self, design: TubeDesign, stage: SecondStage, plants: CascadeClass,
                 timing: dict) -> None:
        n = design.dimension
        self.data = {"rate_hz": design.rate_hz, "position_gain": stage.position_gain,
                     "velocity_gain": stage.velocity_gain,
                     "width_start": list(stage.width_start),
                     "width_floor": list(stage.width_floor), "decay": stage.decay,
                     "class": plants.words(), **timing}
        self.peak_u, self.peak_x2, self.peak_t = [0.0] * n, [0.0] * n, [0.0] * n
        self.worst = {"position": math.inf, "velocity": math.inf, "least": math.inf,
                      "t": 0.0, "i": 0}
        self.top = [0.0, 0.0]

    def judged(self, room: float, vroom: float, t: float, i: int) -> None:
        """Take the position and velocity room of one interval and axis."""
        worst = self.worst
        worst["position"] = min(worst["position"], room)
        worst["velocity"] = min(worst["velocity"], vroom)
        if min(room, vroom) < worst["least"]:
            worst.update(least=min(room, vroom), t=t, i=i)

    def result(self, passed: bool, reason: str, t: float = 0.0, i: int = 0) -> CascadeCheck:
        """The check's outcome; ``t``, ``i``: where it failed."""
        worst, top = self.worst, self.top
        pm, vm = worst["position"], worst["velocity"]
        self.data.update({"position_margin": pm, "velocity_margin": vm,
                          "max_abs_e1": top[0], "max_abs_e2": top[1],
                          "peak_input": list(self.peak_u),
                          "peak_input_time": list(self.peak_t),
                          "peak_velocity": list(self.peak_x2)})
        return CascadeCheck(passed, reason, pm, vm, top[0], top[1], tuple(self.peak_u),
                            tuple(self.peak_x2), worst["t"] if passed else t,
                            worst["i"] if passed else i, self.data, tuple(self.peak_t))


def _rho2(stage: SecondStage, t: np.ndarray) -> np.ndarray:
    """The velocity tube's half-width ``rho2(t) = (rho2_0 - rho2_inf) exp(-decay t) +
    rho2_inf`` at the times ``t`` (K,), per axis: (K, n)."""
    start, floor = np.array(stage.width_start), np.array(stage.width_floor)
    return (start - floor)[None, :] * np.exp(-stage.decay * t[:, None]) + floor[None, :]


def _unfit(stage: SecondStage, samples: TubeSamples, plants: CascadeClass,
           longest: float) -> str:
    """Why no interval can be checked (the class, the velocity tube's floor, the tube's
    width; ``longest`` the longest interval, s), or ``""``."""
    if not 0.0 < plants.g_min <= plants.g_max or longest * plants.drift_slope >= 1.0:
        return "need 0 < g_min <= g_max and h F1 < 1"
    if min(stage.width_floor) < GAMMA_D_MIN:
        return f"rho2_inf is below GAMMA_D_MIN = {GAMMA_D_MIN:g}"
    if (samples.gamma_upper - samples.gamma_lower).min() < GAMMA_D_MIN:
        return f"the tube is narrower than GAMMA_D_MIN = {GAMMA_D_MIN:g}"
    return ""


def check_cascade_sampled(design: TubeDesign, samples: TubeSamples, stage: SecondStage,
                          plants: CascadeClass, initial_velocity, *, delay: float = 0.0,
                          jitter: float = 0.0, compensate: bool = False) -> CascadeCheck:
    """Prove that the sampled cascade keeps ``|e1| < 1`` and ``|e2| < 1`` at and between
    samples for every plant of ``plants`` (module docstring; docs/second-order.md).

    Parameters
    ----------
    design : TubeDesign
        The position tube (``rate_hz``, ``initial_state``).
    samples : TubeSamples
        The deployed tube at ``design``'s rate
        (:func:`~stt_codegen.design.samples.sample_tube`).
    stage : SecondStage
        ``k1``, ``k2``, ``rho2`` to check.
    plants : CascadeClass
    initial_velocity : sequence of float, length n
        ``x2(0)``.
    delay : float
        Largest computation delay, s (``[controller] delay``): the force computed from the
        state read at ``s_k`` acts from ``s_k + lag``, ``lag`` in ``[0, delay]`` (any,
        varying from sample to sample); before, the previous force acts (zero before the
        first).
    jitter : float
        Sampling jitter, s (``[controller] jitter``): ``|s_k - k h| <= jitter``, ``s_0 =
        0``; the controller is called with the nominal ``t = k h``. ``delay + 2 jitter``
        must not exceed ``h``. With both 0 (the default) the check is the one without
        timing, float for float.
    compensate : bool
        ``[controller] compensate_delay``: the law at the state predicted over ``delay``
        (:func:`check_cascade_predicted`, which this returns when ``delay > 0``).

    Returns
    -------
    CascadeCheck

    Raises
    ------
    ValueError
        ``delay`` or ``jitter`` negative, or ``delay + 2 jitter > h``; with
        ``compensate``, a ``jitter`` other than 0.
    """
    if compensate and delay > 0.0:
        if jitter != 0.0:
            raise ValueError(f"jitter = {jitter!r} s must be 0 with compensate")
        return check_cascade_predicted(design, samples, stage, plants, initial_velocity,
                                       delay=delay)
    n = design.dimension
    h = 1.0 / design.rate_hz
    if delay < 0.0 or jitter < 0.0 or delay + 2.0 * jitter > h * (1.0 + 1e-12):
        raise ValueError(f"delay = {delay!r} s and jitter = {jitter!r} s must be >= 0 with "
                         f"delay + 2 jitter <= dt = {h!r} s")
    timed = delay > 0.0 or jitter > 0.0
    # a measurement interval [s_k, s_{k+1}] lasts L in [h - 2 jitter, h + 2 jitter]; the
    # previous force acts for its first `lag` in [0, delay], this one for the rest, a
    # `share` (L - lag) / h of a period (docs/second-order.md, "A computation delay and
    # jitter"): the velocity stage's bounds are affine in (L, lag), the position stage's
    # in L, so their corners cover every L and lag
    longest = h + 2.0 * jitter
    lengths = (h - 2.0 * jitter, longest)
    corners = sorted({(max(0.0, (length - lag) / h), lag) for length in lengths
                      for lag in (0.0, delay)})
    k1, k2 = stage.position_gain, stage.velocity_gain
    g_min, g_max, cpl = plants.g_min, plants.g_max, plants.coupling
    f1, w_amp = plants.drift_slope, plants.disturbance_bound
    f0 = np.broadcast_to(np.asarray(plants.drift_bound, dtype=float).reshape(-1), (n,))
    vbound = plants.velocity_bound
    tally = _Tally(design, stage, plants, {"delay": delay, "jitter": jitter} if timed else {})
    peak_u, peak_x2, peak_t = tally.peak_u, tally.peak_x2, tally.peak_t
    worst, top, data, result = tally.worst, tally.top, tally.data, tally.result
    refused = _unfit(stage, samples, plants, longest if timed else h)
    if refused:
        return result(False, refused)
    lo, hi = samples.gamma_lower, samples.gamma_upper
    enc = enclose_tube(design, samples)
    count = len(enc.t_start)
    half, centre = 0.5 * (hi - lo), 0.5 * (hi + lo)
    rho2_all = _rho2(stage, samples.t)
    rho2 = rho2_all.tolist()
    # the velocity stage's pull and peak on every interval at once (one bisection over the
    # array, the same floats as one interval at a time)
    pull2_all = 2.0 * h * k2 / rho2_all[:count]
    peak2 = peak(rho2_all[:count] / (g_min * pull2_all)).tolist()
    pull1 = (4.0 * h * k1 / (hi - lo)).tolist()
    peak1 = peak(0.5 * (hi - lo) / (4.0 * h * k1 / (hi - lo))).tolist()
    half_l, centre_l = half.tolist(), centre.tolist()
    # with jitter an interval reaches into its neighbours: the tube's enclosure is the
    # worst of intervals k - 1 .. k + 1, in absolute units (then in interval k's coordinates)
    upper_min, lower_max = (worst_near(enc.upper_min, jitter, np.minimum),
                            worst_near(enc.lower_max, jitter, np.maximum))
    upper_max, lower_min = (worst_near(enc.upper_max, jitter, np.maximum),
                            worst_near(enc.lower_min, jitter, np.minimum))
    up_e = ((upper_min - centre[:count]) / half[:count]).tolist()
    low_e = ((lower_max - centre[:count]) / half[:count]).tolist()
    room_up, room_low = upper_min.tolist(), lower_max.tolist()
    width_min = worst_near(enc.width_min, jitter, np.minimum).tolist()
    width_max = (upper_max - lower_min).tolist()
    move = ((lower_max - lower_min) + (upper_max - upper_min)).tolist()
    if timed:
        # s* of each share of a period the own force (the virtual velocity) acts
        shares1 = sorted({length / h for length in lengths})
        peaks1 = {share: peak(0.5 * (hi - lo) / (share * 4.0 * h * k1 / (hi - lo))).tolist()
                  for share in shares1}
        peaks2 = {share: peak(rho2_all[:count] / (g_min * share * pull2_all)).tolist()
                  if share > 0.0 else np.full((count, n), 1.0 - 1e-15).tolist()
                  for share in sorted({share for share, _ in corners})}
        # rho2 decreases: its least on a measurement interval is at t_{k+1} + jitter
        late = _rho2(stage, samples.t[1:count + 1] + jitter).tolist()
    x1_0 = np.array(design.initial_state, dtype=float)
    e1_0 = ((x1_0 - centre[0]) / half[0]).tolist()
    r0 = [-(4.0 * k1 / (2.0 * half_l[0][i])) * phi_scalar(e1_0[i]) for i in range(n)]
    x2_0 = [float(v) for v in initial_velocity]
    e2_0 = [(x2_0[i] - r0[i]) / rho2[0][i] for i in range(n)]
    box1 = [[v, v] for v in e1_0]
    box2 = [[v, v] for v in e2_0]
    u_prev = [0.0] * n                                    # no force before the first
    every = max(1, count // PROGRESS_REPORTS)
    for k in range(count):
        t = float(samples.t[k])
        if k % every == 0:
            report("cascade certificate", k / count,
                   f"the sampled cascade's certificate: t = {t:.3g} s of {samples.t[-1]:.3g} s")
        reach1 = [max(-a, b) for a, b in box1]
        reach2 = [max(-a, b) for a, b in box2]
        top[0], top[1] = max(top[0], max(reach1)), max(top[1], max(reach2))
        for name, reach in (("e1", reach1), ("e2", reach2)):
            if max(reach) > E_MAX:
                i = int(np.argmax(reach))
                return result(False, f"|{name}_{i}| may reach {max(reach):.6g} at t = "
                              f"{t:.4f} s, beyond the clamp E_MAX", t, i)
        rho_k, rho_n = rho2[k], rho2[k + 1]
        u_abs = [2.0 * k2 / rho_k[i] * phi_scalar(reach2[i]) for i in range(n)]
        u_sq = sum(v * v for v in u_abs)
        u_prev_sq = sum(v * v for v in u_prev)
        next1, next2 = [], []
        for i in range(n):
            if u_abs[i] > peak_u[i]:
                peak_u[i], peak_t[i] = u_abs[i], t
            others = math.sqrt(max(u_sq - u_abs[i] ** 2, 0.0))
            z_abs = reach2[i] * rho_k[i]
            r_abs = 4.0 * k1 / (2.0 * half_l[k][i]) * phi_scalar(reach1[i])
            if not timed:
                push_free = g_max * u_abs[i] + cpl * others + f0[i] + w_amp  # w/o F1
                speed = (r_abs + z_abs + h * push_free) / (1.0 - h * f1)
            else:
                # the force is u_{k-1} for the lag, then u_k: x2 moves under the larger
                force_old = g_max * u_prev[i] + cpl * math.sqrt(
                    max(u_prev_sq - u_prev[i] ** 2, 0.0)) if delay > 0.0 else 0.0
                force = max(g_max * u_abs[i] + cpl * others, force_old)
                speed = ((r_abs + z_abs + longest * (force + f0[i] + w_amp))
                         / (1.0 - longest * f1))
            peak_x2[i] = max(peak_x2[i], speed)
            if vbound is not None and speed >= vbound[i]:
                return result(False, f"|x2_{i}| may reach {speed:.4g} on [{t:.4f}, "
                              f"{t + h:.4f}] s, beyond velocity_bound {vbound[i]:g} (the "
                              "drift bound is declared within it)", t, i)
            drift = f0[i] + f1 * speed + w_amp
            if not timed:
                accel = g_max * u_abs[i] + cpl * others + drift
                # position stage: law (13) with g = 1 and a displacement <= tau (Z + h A/2)
                shift = h * z_abs + 0.5 * h * h * accel
                p_lo, p_hi, x_lo, x_hi = axis_interval(
                    box1[i][0], box1[i][1], centre_l[k][i], half_l[k][i], pull1[k][i], 1.0,
                    1.0, peak1[k][i], shift)
            else:
                accel = force + drift                     # the old force's and the new's
                shift = longest * z_abs + 0.5 * longest * longest * accel
                p_lo, p_hi, x_lo, x_hi = _union(axis_interval(
                    box1[i][0], box1[i][1], centre_l[k][i], half_l[k][i],
                    share * pull1[k][i], 1.0, 1.0, peaks1[share][k][i], shift)
                    for share in shares1)
            e_lo = (p_lo - centre_l[k][i]) / half_l[k][i]
            e_hi = (p_hi - centre_l[k][i]) / half_l[k][i]
            room = min(up_e[k][i] - e_hi, e_lo - low_e[k][i])
            worst["position"] = min(worst["position"], room)
            if room <= 0.0:
                return result(False, f"the position may leave its tube in dimension {i} on "
                              f"[{t:.4f}, {t + h:.4f}] s (the enclosure of x1 reaches "
                              f"{-room:.3g} half-widths beyond its edge)", t, i)
            gap = min(room_up[k][i] - p_hi, p_lo - room_low[k][i])
            e1_path = max(1.0 - 2.0 * gap / width_max[k][i], reach1[i])
            dr = virtual_velocity_change(k1, longest if timed else h, reach1[i], e1_path,
                                         speed, move[k][i], width_min[k][i], width_max[k][i])
            # velocity stage: law (13)'s transform on |z| < rho2, the change of r on top
            if not timed:
                pull2, s_peak = 2.0 * h * k2 / rho_k[i], peak2[k][i]
                q_lo, q_hi, z_lo, z_hi = axis_interval(
                    box2[i][0], box2[i][1], 0.0, rho_k[i], pull2, g_min, g_max, s_peak,
                    h * drift, h * others, cpl, 0.0)
                edge = rho_n[i] * (1.0 - RHO_ROUNDING)
            else:
                pull2 = 2.0 * h * k2 / rho_k[i]
                old = force_old + drift                   # |x2_dot| under u_{k-1}
                q_lo, q_hi, z_lo, z_hi = _union(axis_interval(
                    box2[i][0], box2[i][1], 0.0, rho_k[i], share * pull2, g_min, g_max,
                    peaks2[share][k][i], share * h * drift + lag * old,
                    share * h * others, cpl, 0.0) for share, lag in corners)
                # while the previous force acts, z moves from z(s_k) by at most this
                q_lo = min(q_lo, box2[i][0] * rho_k[i] - delay * old)
                q_hi = max(q_hi, box2[i][1] * rho_k[i] + delay * old)
                edge = late[k][i] * (1.0 - RHO_ROUNDING)
            vroom = 1.0 - max(-(q_lo - dr), q_hi + dr) / edge
            worst["velocity"] = min(worst["velocity"], vroom)
            if min(room, vroom) < worst["least"]:
                worst.update(least=min(room, vroom), t=t, i=i)
            if vroom <= 0.0:
                return result(False, f"the velocity error may leave its tube in dimension "
                              f"{i} on [{t:.4f}, {t + h:.4f}] s (|e2| up to "
                              f"{1.0 - vroom:.4g}; the change of r alone is {dr / edge:.3g} "
                              "of rho2)", t, i)
            box_n = [(x_lo - centre_l[k + 1][i]) / half_l[k + 1][i],
                     (x_hi - centre_l[k + 1][i]) / half_l[k + 1][i]]
            reach_n = max(-box_n[0], box_n[1], reach1[i])
            if reach_n >= 1.0:
                return result(False, f"|e1_{i}| may reach {reach_n:.6g} at t = {t + h:.4f} s",
                              t, i)
            # at the next sample: over the interval's length, h without jitter (the bound
            # is convex in the length: its ends cover the range)
            dr_end = min(dr, max(step_velocity_change(
                k1, length, box1[i][0], box1[i][1],
                (centre_l[k][i] - centre_l[k + 1][i]) / half_l[k + 1][i],
                half_l[k][i] / half_l[k + 1][i], reach_n, half_l[k][i], half_l[k + 1][i],
                shift) for length in (sorted(set(lengths)) if timed else (h,))))
            next1.append(box_n)
            next2.append([(z_lo - dr_end) / rho_n[i], (z_hi + dr_end) / rho_n[i]])
        if timed:
            u_prev = u_abs
        box1, box2 = next1, next2
    top[0] = max(top[0], max(max(-a, b) for a, b in box1))
    top[1] = max(top[1], max(max(-a, b) for a, b in box2))
    data["horizon"] = float(samples.t[count])
    return result(True, "")


def check_cascade_predicted(design: TubeDesign, samples: TubeSamples, stage: SecondStage,
                            plants: CascadeClass, initial_velocity, *,
                            delay: float) -> CascadeCheck:
    """Prove that the cascade with the delay-compensating prediction keeps ``|e1| < 1`` and
    ``|e2| < 1`` at every instant of the horizon for every plant of ``plants``.

    The loop (``[controller] compensate_delay``) reads ``x(s_k)`` at ``s_k = k h``,
    predicts the state at ``a_k = s_k + delay`` from the force ``u_{k-1}`` acting until
    then (eq. (P0''), :func:`~stt_codegen.tube.cascade.cascade_predictor`), computes
    ``u_k`` by the cascade law at ``(x_hat_k, t_k)`` and applies it on ``[a_k,
    a_{k+1}]``. The argument (docs/second-order.md, "Compensating a delay", (C1)-(C4)):
    the prediction misses ``x(a_k)`` by ``eta2 <= delay A'`` in velocity and ``eta1 <=
    (delay^2 / 2) A'`` in position, ``A'`` the bound of ``|(g - g_mid) u_{k-1} + f + w|``
    (C1); on the actuation interval both stages are the plain check's, started at the
    predicted boxes, with the misses added to the position and the velocity error and
    the change of ``r`` taken from ``(x1_hat_k, t_k)`` (C2, C3), judged against the tubes
    over intervals ``k`` and ``k + 1``; the next predicted boxes are the true state's at
    ``a_{k+1}`` widened by the next misses (C4). The predicted state is required inside
    both tubes at every sample.

    Parameters
    ----------
    design : TubeDesign
        The position tube (``rate_hz``, ``initial_state``).
    samples : TubeSamples
        The deployed tube at ``design``'s rate.
    stage : SecondStage
        ``k1``, ``k2``, ``rho2`` to check.
    plants : CascadeClass
    initial_velocity : sequence of float, length n
        ``x2(0)``.
    delay : float
        The computation delay, s, in ``(0, h]``.

    Returns
    -------
    CascadeCheck
        ``max_abs_e1``, ``max_abs_e2``: the bounds at the samples of the predicted state's
        errors; ``peak_input``: of ``|u_k|``; ``peak_velocity``: of ``|x2|`` on the
        actuation intervals.

    Raises
    ------
    ValueError
        ``delay`` outside ``(0, h]``.
    """
    n = design.dimension
    h = 1.0 / design.rate_hz
    if not 0.0 < delay <= h * (1.0 + 1e-12):
        raise ValueError(f"delay = {delay!r} s must lie in (0, dt = {h!r}] s")
    k1, k2 = stage.position_gain, stage.velocity_gain
    g_min, g_max, cpl = plants.g_min, plants.g_max, plants.coupling
    f1, w_amp = plants.drift_slope, plants.disturbance_bound
    f0 = np.broadcast_to(np.asarray(plants.drift_bound, dtype=float).reshape(-1), (n,))
    deviation = 0.5 * (g_max - g_min)                     # |g_ii - g_mid|
    g_mid = 0.5 * (g_max + g_min)
    share = 1.0 - min(delay / h, 1.0)          # of a period x_hat's step is uncertain
    mix_lo = share * g_min + (1.0 - share) * g_mid
    mix_hi = share * g_max + (1.0 - share) * g_mid
    vbound = plants.velocity_bound
    tally = _Tally(design, stage, plants, {"delay": delay, "jitter": 0.0,
                                           "compensate_delay": True})
    peak_u, peak_x2, peak_t = tally.peak_u, tally.peak_x2, tally.peak_t
    top, result, judged = tally.top, tally.result, tally.judged
    refused = _unfit(stage, samples, plants, h)
    if refused:
        return result(False, refused)
    lo, hi = samples.gamma_lower, samples.gamma_upper
    enc = enclose_tube(design, samples)
    count = len(enc.t_start)
    half, centre = 0.5 * (hi - lo), 0.5 * (hi + lo)
    rho2 = _rho2(stage, samples.t).tolist()
    # rho2 decreases: its least on [a_k, a_{k+1}] is at t_{k+1} + delay
    late = _rho2(stage, samples.t[1:count + 1] + delay).tolist()
    pull2_all = 2.0 * h * k2 / np.array(rho2[:count])
    peak2 = peak(np.array(rho2[:count]) / (g_min * pull2_all)).tolist()
    pull1 = (4.0 * h * k1 / (hi - lo)).tolist()
    peak1 = peak(0.5 * (hi - lo) / (4.0 * h * k1 / (hi - lo))).tolist()
    half_l, centre_l = half.tolist(), centre.tolist()
    width_max_own = enc.upper_max - enc.lower_min
    move_own = (enc.lower_max - enc.lower_min) + (enc.upper_max - enc.upper_min)
    # over the actuation interval [t_k + delay, t_{k+1} + delay] (absolute units)
    act = enclose_later(design, samples, delay, delay)
    room_up, room_low = act.upper_min, act.lower_max
    up_e = ((room_up - centre[:count]) / half[:count]).tolist()
    low_e = ((room_low - centre[:count]) / half[:count]).tolist()
    room_up, room_low = room_up.tolist(), room_low.tolist()
    width_max_a = (act.upper_max - act.lower_min).tolist()
    # r changes from (x1_hat_k, t_k) to (x1(t), t), t <= t_{k+1} + delay: the tube's span
    # and widths over [t_k, t_{k+1} + delay]
    whole = enclose_later(design, samples, 0.0, delay)
    move_r = ((whole.lower_max - whole.lower_min) + (whole.upper_max - whole.upper_min)).tolist()
    width_min_r = whole.width_min.tolist()
    width_max_r = (whole.upper_max - whole.lower_min).tolist()
    width_min, width_max, move = (enc.width_min.tolist(), width_max_own.tolist(),
                                  move_own.tolist())

    def r_of(e1: float, k: int, i: int) -> float:
        return -(4.0 * k1 / (2.0 * half_l[k][i])) * phi_scalar(e1)

    # (C0) before the first force acts: [0, delay], no force
    x1_0 = [float(v) for v in design.initial_state]
    x2_0 = [float(v) for v in initial_velocity]
    edge0 = _rho2(stage, np.array([delay]))[0].tolist()
    box1, box2, eta1, eta2 = [], [], [], []
    for i in range(n):
        speed = (abs(x2_0[i]) + delay * (f0[i] + w_amp)) / (1.0 - delay * f1)
        peak_x2[i] = speed
        if vbound is not None and speed >= vbound[i]:
            return result(False, f"|x2_{i}| may reach {speed:.4g} on [0, {delay:.4g}] s, "
                          f"beyond velocity_bound {vbound[i]:g}", 0.0, i)
        accel = f0[i] + f1 * speed + w_amp
        p_lo, p_hi = x1_0[i] - delay * speed, x1_0[i] + delay * speed
        e1_0 = (x1_0[i] - centre_l[0][i]) / half_l[0][i]
        room = min(float(enc.upper_min[0][i]) - p_hi,
                   p_lo - float(enc.lower_max[0][i])) / half_l[0][i]
        if room <= 0.0 or abs(e1_0) >= 1.0:
            return result(False, f"the position may leave its tube in dimension {i} on "
                          f"[0, {delay:.4g}] s, before the first force acts", 0.0, i)
        gap = room * half_l[0][i]
        dr = virtual_velocity_change(k1, 1.0, abs(e1_0),
                                     max(1.0 - 2.0 * gap / width_max[0][i], abs(e1_0)),
                                     delay * speed, move[0][i], width_min[0][i],
                                     width_max[0][i])
        z_0 = x2_0[i] - r_of(e1_0, 0, i)
        vroom = 1.0 - (abs(z_0) + delay * accel + dr) / (edge0[i] * (1.0 - RHO_ROUNDING))
        judged(room, vroom, 0.0, i)
        if vroom <= 0.0:
            return result(False, f"the velocity error may leave its tube in dimension {i} "
                          f"on [0, {delay:.4g}] s, before the first force acts", 0.0, i)
        # the prediction at s_0 = 0 (u_{-1} = 0) and its miss (C1)
        e1_hat = (x1_0[i] + delay * x2_0[i] - centre_l[0][i]) / half_l[0][i]
        if abs(e1_hat) >= 1.0:
            return result(False, f"the predicted position leaves its tube in dimension {i} "
                          "at t = 0", 0.0, i)
        e2_hat = (x2_0[i] - r_of(e1_hat, 0, i)) / rho2[0][i]
        box1.append([e1_hat, e1_hat])
        box2.append([e2_hat, e2_hat])
        eta2.append(delay * accel)
        eta1.append(0.5 * delay * delay * accel)
    every = max(1, count // PROGRESS_REPORTS)
    for k in range(count):
        t = float(samples.t[k])
        if k % every == 0:
            report("cascade certificate", k / count, "the predicted cascade's certificate: "
                   f"t = {t:.3g} s of {samples.t[-1]:.3g} s")
        reach1 = [max(-a, b) for a, b in box1]
        reach2 = [max(-a, b) for a, b in box2]
        top[0], top[1] = max(top[0], max(reach1)), max(top[1], max(reach2))
        for name, reach in (("e1", reach1), ("e2", reach2)):
            if max(reach) >= 1.0:
                i = int(np.argmax(reach))
                return result(False, f"|{name}_{i}| of the predicted state may reach "
                              f"{max(reach):.6g} at t = {t:.4f} s (the check needs it inside "
                              "its tube)", t, i)
        rho_k, rho_n = rho2[k], rho2[k + 1]
        u_abs = [2.0 * k2 / rho_k[i] * phi_scalar(reach2[i]) for i in range(n)]
        u_sq = sum(v * v for v in u_abs)
        next1, next2, next_eta1, next_eta2 = [], [], [], []
        for i in range(n):
            if u_abs[i] > peak_u[i]:
                peak_u[i], peak_t[i] = u_abs[i], t
            others = math.sqrt(max(u_sq - u_abs[i] ** 2, 0.0))
            z_abs = reach2[i] * rho_k[i]
            r_abs = 4.0 * k1 / (2.0 * half_l[k][i]) * phi_scalar(reach1[i])
            force = g_max * u_abs[i] + cpl * others
            # (C2) |x2| on [a_k, a_{k+1}]: from x2_hat = r_k + z_hat, the miss, the interval
            speed = (r_abs + z_abs + eta2[i] + h * (force + f0[i] + w_amp)) / (1.0 - h * f1)
            peak_x2[i] = max(peak_x2[i], speed)
            if vbound is not None and speed >= vbound[i]:
                return result(False, f"|x2_{i}| may reach {speed:.4g} on [{t + delay:.4f}, "
                              f"{t + h + delay:.4f}] s, beyond velocity_bound {vbound[i]:g} "
                              "(the drift bound is declared within it)", t, i)
            drift = f0[i] + f1 * speed + w_amp
            # (C2) the position stage: law (13) with g = 1 at x1_hat, x1(a_k) = x1_hat + miss
            shift = h * (z_abs + eta2[i]) + 0.5 * h * h * (force + drift)
            p_lo, p_hi, x_lo, x_hi = axis_interval(
                box1[i][0], box1[i][1], centre_l[k][i], half_l[k][i], pull1[k][i], 1.0, 1.0,
                peak1[k][i], shift)
            p_lo, p_hi, x_lo, x_hi = p_lo - eta1[i], p_hi + eta1[i], x_lo - eta1[i], x_hi + eta1[i]
            room = min(up_e[k][i] - (p_hi - centre_l[k][i]) / half_l[k][i],
                       (p_lo - centre_l[k][i]) / half_l[k][i] - low_e[k][i])
            if room <= 0.0:
                judged(room, math.inf, t, i)
                return result(False, f"the position may leave its tube in dimension {i} on "
                              f"[{t + delay:.4f}, {t + h + delay:.4f}] s (the enclosure of x1 "
                              f"reaches {-room:.3g} half-widths beyond its edge)", t, i)
            gap = min(room_up[k][i] - p_hi, p_lo - room_low[k][i])
            e1_path = max(1.0 - 2.0 * gap / width_max_a[k][i], reach1[i])
            # (C3) |r(x1(t), t) - r(x1_hat_k, t_k)| for t in [a_k, a_{k+1}]
            dr = virtual_velocity_change(k1, 1.0, reach1[i], e1_path, eta1[i] + h * speed,
                                         move_r[k][i], width_min_r[k][i], width_max_r[k][i])
            q_lo, q_hi, z_lo, z_hi = axis_interval(
                box2[i][0], box2[i][1], 0.0, rho_k[i], 2.0 * h * k2 / rho_k[i], g_min, g_max,
                peak2[k][i], h * drift, h * others, cpl, 0.0)
            spread = eta2[i] + dr
            vroom = 1.0 - max(-(q_lo - spread), q_hi + spread) / (late[k][i]
                                                                   * (1.0 - RHO_ROUNDING))
            judged(room, vroom, t, i)
            if vroom <= 0.0:
                return result(False, f"the velocity error may leave its tube in dimension "
                              f"{i} on [{t + delay:.4f}, {t + h + delay:.4f}] s (|e2| up to "
                              f"{1.0 - vroom:.4g}; the change of r alone is "
                              f"{dr / late[k][i]:.3g} of rho2)", t, i)
            # (C4) the next prediction, x_hat_{k+1} = x(s_{k+1}) + the prediction over the
            # delay: from x_hat_k, the miss, the share of the period from a_k to s_{k+1}
            # under the class, and the rest at g_mid exactly
            shift_hat = (eta1[i] + h * (z_abs + eta2[i]) + 0.5 * (h * h - delay * delay)
                         * (force + drift) + 0.5 * delay * delay * g_mid * u_abs[i])
            _, _, xh_lo, xh_hi = axis_interval(
                box1[i][0], box1[i][1], centre_l[k][i], half_l[k][i], pull1[k][i], 1.0, 1.0,
                peak1[k][i], shift_hat)
            box_n = [(xh_lo - centre_l[k + 1][i]) / half_l[k + 1][i],
                     (xh_hi - centre_l[k + 1][i]) / half_l[k + 1][i]]
            reach_n = max(-box_n[0], box_n[1])
            if reach_n >= 1.0:
                return result(False, f"|e1_{i}| of the predicted state may reach "
                              f"{reach_n:.6g} at t = {t + h:.4f} s (the check needs it "
                              "inside its tube)", t, i)
            pull2 = 2.0 * h * k2 / rho_k[i]
            _, _, zh_lo, zh_hi = axis_interval(
                box2[i][0], box2[i][1], 0.0, rho_k[i], pull2, mix_lo, mix_hi,
                peak_scalar(rho_k[i] / (mix_lo * pull2)), share * h * drift + eta2[i],
                h * others, share * cpl, 0.0)       # the other axes: share * g's rows
            # |r(x1_hat_{k+1}, t_{k+1}) - r(x1_hat_k, t_k)|: x1_hat moves by h r_k and at
            # most shift_hat beyond it
            dr_end = min(virtual_velocity_change(
                k1, 1.0, reach1[i], max(reach1[i], reach_n), h * r_abs + shift_hat,
                move[k][i], width_min[k][i], width_max[k][i]), step_velocity_change(
                k1, h, box1[i][0], box1[i][1],
                (centre_l[k][i] - centre_l[k + 1][i]) / half_l[k + 1][i],
                half_l[k][i] / half_l[k + 1][i], max(reach1[i], reach_n), half_l[k][i],
                half_l[k + 1][i], shift_hat))
            # the miss of that prediction, which u_k makes over [s_{k+1}, a_{k+1}] (C1)
            miss = deviation * u_abs[i] + cpl * others + drift
            next1.append(box_n)
            next2.append([(zh_lo - dr_end) / rho_n[i], (zh_hi + dr_end) / rho_n[i]])
            next_eta1.append(0.5 * delay * delay * miss)
            next_eta2.append(delay * miss)
        box1, box2, eta1, eta2 = next1, next2, next_eta1, next_eta2
    top[0] = max(top[0], max(max(-a, b) for a, b in box1))
    top[1] = max(top[1], max(max(-a, b) for a, b in box2))
    tally.data["horizon"] = float(samples.t[count])
    return result(True, "")
