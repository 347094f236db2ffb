"""Sampled-data check: the deployed, sampled law (13) keeps the plant in the tube.

Theorem 4.1 is a continuous-time result. The deployed controller reads ``x(t_k)`` at
``t_k = k dt``, computes ``u_k`` by law (13) with its clamps and holds it until
``t_{k+1}`` (zero-order hold). This module proves, for every plant of the spec's
``[assumptions]`` (:class:`~stt_codegen.spec.loader.Assumptions`), that ``|e_i| < 1`` at
and between samples on the whole horizon of the tube's certificate. The condition and
its proof are in ``docs/sampled-data.md``; in short, per dimension ``i`` and sampling
interval ``[t_k, t_k + dt]``:

* ``x_dot_i = g_ii u_i + d_i`` with ``g_ii`` in ``[g_min, g_max]`` (a diagonal entry of
  ``g`` is one of its symmetric part) and
  ``|d_i| <= D_i = drift_bound + disturbance_bound + (h + s) |u_{-i}|``, where
  ``h = (g_max - g_min) / 2`` bounds the off-diagonal part of a row of the symmetric part,
  ``s`` (``input_gain_skew``) that of the skew part, and ``u_{-i}`` the other inputs;
* ``u`` is held, so ``x_i(t)`` lies between two lines through ``x_i(t_k)``;
* if every ``|e_j(t_k)| <= level_j``, the inputs are bounded, and the lines must stay
  strictly inside the certified enclosure of the tube on the interval
  (:func:`~stt_codegen.design.certificate.enclose_tube`) and end with
  ``|e_i(t_{k+1})| <= level_i``.

The box ``|e_i| <= level_i`` is then invariant at the samples (induction on ``k``), and
``x`` stays strictly inside the tube between them. ``e(t_k)`` ranges over a partition
of ``[0, level_i]`` (and its mirror), and every cell is bounded by monotonicity, so no
point is skipped.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..design.certificate import Certificate, certify_tube, enclose_tube
from ..design.gain import derived_gain, gain_derivation
from ..design.samples import TubeSamples, sample_tube
from ..spec.loader import Assumptions, LinearPlant, Spec
from ..tube.parameters import E_MAX, GAMMA_D_MIN, TubeDesign
from .check import Check

#: Sampling-rate multiples tried by :func:`lowest_rate`, in increasing order.
RATE_FACTORS = (0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 2.0, 2.5, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0)


@dataclass(frozen=True)
class SampledCheck:
    """Outcome of :func:`check_sampled`.

    Attributes
    ----------
    passed : bool
        The sufficient condition holds: no plant of the assumptions leaves the tube.
    level : float
        The proved bound of ``max_i |e_i(t_k)|`` at the samples (the smallest level that
        works); when failed, the level with the smallest violation.
    margin : float
        Smallest relative room left, ``min`` over intervals and dimensions of the room to
        the tube's edge between samples divided by the tube's half-width, and of
        ``level - |e_i(t_{k+1})|``; negative when failed.
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
        (read by :func:`stt_codegen.verify.actuator.sampled_error_bound` for the input
        bound); ``None`` otherwise.
    """

    passed: bool
    level: float
    margin: float
    time: float
    dimension: int
    reason: str
    data: dict = field(default_factory=dict)
    abs_e: np.ndarray | None = field(default=None, compare=False, repr=False)


def _phi(s: np.ndarray) -> np.ndarray:
    """``|u_i| gamma_d_i / (4 k) = epsilon_i / (1 - e_i^2)`` of law (13) at ``|e_i| = s``."""
    return 2.0 * np.arctanh(s) / (1.0 - s * s)


def _phi_slope(s: np.ndarray) -> np.ndarray:
    """``d phi / d s = (2 + 4 s atanh(s)) / (1 - s^2)^2`` (positive, increasing)."""
    return (2.0 + 4.0 * s * np.arctanh(s)) / (1.0 - s * s) ** 2


def _peak(ratio: np.ndarray) -> np.ndarray:
    """``s* = argmax_s (s - phi(s) / ratio)`` on ``[0, 1)``: ``phi'(s*) = ratio``, 0 if
    ``ratio <= phi'(0) = 2``. Bisection (``phi'`` is increasing)."""
    lo, hi = np.zeros_like(ratio), np.full_like(ratio, 1.0 - 1e-15)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        up = _phi_slope(mid) < ratio
        lo, hi = np.where(up, mid, lo), np.where(up, hi, mid)
    return np.where(ratio <= 2.0, 0.0, lo)


def _phi1(s: float) -> float:
    return 2.0 * math.atanh(s) / (1.0 - s * s)


def check_sampled(design: TubeDesign, samples: TubeSamples, assumptions: Assumptions,
                  gain: float | None = None) -> SampledCheck:
    """Prove that the sampled closed loop keeps ``|e_i| < 1`` at and between samples.

    A sufficient condition, checked by propagating an enclosure of ``e(t_k)`` from
    ``e(0)`` (``docs/sampled-data.md``): on every sampling interval, for every plant
    ``x_dot = f(x) + g(x) u + w`` of ``assumptions`` and every ``e(t_k)`` in the
    enclosure, ``x`` stays strictly inside the tube's certified enclosure until
    ``t_{k+1}``, and ``e(t_{k+1})`` lies in the next enclosure, inside
    ``[-E_MAX, E_MAX]``.

    Parameters
    ----------
    design : TubeDesign
        Gives ``rate_hz``, ``x(0)`` and, unless ``gain`` is given, ``k`` of law (13).
    samples : TubeSamples
        The deployed tube at the rate of ``design``
        (:func:`~stt_codegen.design.samples.sample_tube`).
    assumptions : Assumptions
        The declared plant bounds; ``input_gain[0] > 0`` is needed.
    gain : float, optional
        ``k`` to check instead of ``design.gain``.

    Returns
    -------
    SampledCheck
    """
    k_gain = design.gain if gain is None else float(gain)
    n = design.dimension
    dt = 1.0 / design.rate_hz
    g_min, g_max = assumptions.input_gain
    coupling = assumptions.input_gain_coupling
    push = assumptions.drift_bound + assumptions.disturbance_bound
    lo, hi = samples.gamma_lower, samples.gamma_upper
    width = hi - lo
    data = {"gain": k_gain, "rate_hz": design.rate_hz, "input_gain": [g_min, g_max],
            "input_gain_skew": assumptions.input_gain_skew,
            "input_gain_coupling": assumptions.input_gain_coupling,
            "drift_bound": assumptions.drift_bound,
            "disturbance_bound": assumptions.disturbance_bound}

    def fail(reason: str, margin: float, t: float, i: int, level: float) -> SampledCheck:
        return SampledCheck(False, level, margin, t, i, reason, data)

    if g_min <= 0:
        return fail("input_gain[0] must be positive (Assumption 2): law (13) cannot pull "
                    "the state back otherwise", -math.inf, 0.0, 0, math.nan)
    if width.min() < GAMMA_D_MIN:
        return fail(f"the tube is narrower than GAMMA_D_MIN = {GAMMA_D_MIN:g} at a sample",
                    -math.inf, 0.0, 0, math.nan)
    enclosure = enclose_tube(design, samples)
    half = 0.5 * width
    centre = 0.5 * (hi + lo)
    pull = 4.0 * dt * k_gain / width                      # (K+1, n): dt |u| / phi per unit g
    peak_out = _peak(half / (pull * g_min)).tolist()      # maximizer of the outward end
    half_l, centre_l, pull_l = half.tolist(), centre.tolist(), pull.tolist()
    up_l, low_l = enclosure.upper_min.tolist(), enclosure.lower_max.tolist()
    x0 = np.array(design.initial_state)
    e = ((x0 - centre[0]) / half[0]).tolist()
    box = [[v, v] for v in e]                             # enclosure of e(t_k), per dim
    worst, worst_t, worst_i, top = math.inf, 0.0, 0, max(abs(v) for v in e)
    abs_e = []                                            # the bound of |e(t_k)|, per sample
    for k in range(len(enclosure.t_start)):
        t = float(samples.t[k])
        reach = [max(-a, b) for a, b in box]
        abs_e.append(reach)
        if max(reach) > E_MAX:
            i = int(np.argmax(reach))
            return fail(f"|e_{i}| may reach {max(reach):.6g} at t = {t:.4f} s, beyond the "
                        f"clamp E_MAX", -math.inf, t, i, max(reach))
        u_max = [k_gain * 4.0 * _phi1(r) / (2.0 * half_l[k][j]) for j, r in enumerate(reach)]
        total = sum(v * v for v in u_max)
        new_box = []
        for i in range(n):
            a, b = box[i]
            h0, c0, p = half_l[k][i], centre_l[k][i], pull_l[k][i]
            h1, c1 = half_l[k + 1][i], centre_l[k + 1][i]
            d = dt * (push + coupling * math.sqrt(max(total - u_max[i] ** 2, 0.0)))
            path_lo = end_lo = math.inf
            path_hi = end_hi = -math.inf
            for sign, s_a, s_b in ((1.0, max(a, 0.0), b), (-1.0, max(-b, 0.0), -a)):
                if s_b < s_a or (s_b == 0.0 and sign < 0):
                    continue
                start_a, start_b = sign * c0 + s_a * h0, sign * c0 + s_b * h0
                s_star = min(max(peak_out[k][i], s_a), s_b)
                out_max = sign * c0 + s_star * h0 - p * g_min * _phi1(s_star) + d
                in_min = min(start_a - p * g_max * _phi1(s_a),
                             start_b - p * g_max * _phi1(s_b)) - d
                low, high = min(start_a, in_min), max(start_b, out_max)
                if sign > 0:
                    path_lo, path_hi = min(path_lo, low), max(path_hi, high)
                    end_lo, end_hi = min(end_lo, in_min), max(end_hi, out_max)
                else:
                    path_lo, path_hi = min(path_lo, -high), max(path_hi, -low)
                    end_lo, end_hi = min(end_lo, -out_max), max(end_hi, -in_min)
            room = min(up_l[k][i] - path_hi, path_lo - low_l[k][i]) / h0
            if room < worst:
                worst, worst_t, worst_i = room, t, i
            if room <= 0.0:
                return fail(f"a plant of the assumptions may leave the tube in dimension {i} "
                            f"on [{t:.4f}, {t + dt:.4f}] s (the enclosure of x reaches "
                            f"{-room:.3g} half-widths beyond its edge)", room, t, i, top)
            new_box.append([(end_lo - c1) / h1, (end_hi - c1) / h1])
        box = new_box
        top = max(top, max(max(-a, b) for a, b in box))
    data.update({"max_abs_e": top, "margin": worst})
    abs_e.append([max(-a, b) for a, b in box])
    return SampledCheck(True, top, worst, worst_t, worst_i, "", data, np.array(abs_e))


def lowest_rate(design: TubeDesign, spec: Spec, assumptions: Assumptions,
                explicit_gain: float | None = None) -> tuple[float | None, float | None]:
    """The lowest of ``rate_hz`` times :data:`RATE_FACTORS` at which the design holds.

    At each rate the tube keeps its circumvents and segments, is certified again
    (:func:`~stt_codegen.design.certificate.certify_tube`: the deployed ``alpha`` and the
    sampling-rate check depend on the rate), and the sampled check
    (:func:`check_sampled`) must pass with the gain the design would use there:
    ``explicit_gain`` if given, else :func:`~stt_codegen.design.gain.derived_gain` at that
    rate's certified narrowest width. The largest factor is tried first; if it fails, no factor
    is reported.

    Parameters
    ----------
    design : TubeDesign
    spec : Spec
        For the certificate (state space, obstacles, target).
    assumptions : Assumptions
    explicit_gain : float, optional

    Returns
    -------
    rate_hz, gain : float or None
        ``(None, None)`` when no factor tried works.
    """
    def passes(factor: float) -> tuple[bool, float]:
        trial = replace(design, rate_hz=design.rate_hz * factor)
        certificate = certify_tube(trial, spec)
        gain = (explicit_gain if explicit_gain is not None
                else derived_gain(certificate.min_width, trial.rate_hz, assumptions))
        if not certificate.passed:
            return False, gain
        return check_sampled(trial, sample_tube(trial), assumptions, gain).passed, gain

    # the fastest rate first: when even it fails (coupling beyond what any rate can
    # handle), one check answers instead of all of them
    ok, fastest_gain = passes(RATE_FACTORS[-1])
    if not ok:
        return None, None
    for factor in RATE_FACTORS[:-1]:
        ok, gain = passes(factor)
        if ok:
            return design.rate_hz * factor, gain
    return design.rate_hz * RATE_FACTORS[-1], fastest_gain


# --------------------------------------------------------------------------- verify


def _bounds_words(a: Assumptions) -> str:
    g_min, g_max = a.input_gain
    source = "declared" if a.declared else "defaults: declare [assumptions] for your plant"
    return (f"eig((g + g^T)/2) in [{g_min:g}, {g_max:g}], |skew part| <= "
            f"{a.input_gain_skew:g}, row coupling <= {a.input_gain_coupling:g}, |f| <= "
            f"{a.drift_bound:g}, |w| <= {a.disturbance_bound:.3g} ({source})")


def sampled_checks(spec: Spec, design: TubeDesign, samples: TubeSamples,
                   certificate: Certificate) -> list[Check]:
    """The checks of ``stt-codegen verify`` for the sampled closed loop.

    ``sampled.gain``: ``k`` is below the linearized stability limit at the narrowest tube
    for ``g_max``, with the derivation (:func:`~stt_codegen.design.gain.gain_derivation`)
    in words. ``sampled.tube_kept``: :func:`check_sampled` for the spec's assumptions;
    when it fails, the lowest rate that passes (:func:`lowest_rate`).

    Parameters
    ----------
    spec : Spec
    design : TubeDesign
        With its gain set (the spec's ``controller.gain`` or the derived one).
    samples : TubeSamples
        ``design``'s tube at its sampling instants.
    certificate : Certificate
        ``design``'s tube certificate (its ``non-empty`` margin is the width the gain is
        derived from).

    Returns
    -------
    list of Check
    """
    a = spec.assumptions
    narrowest = certificate.margin("non-empty")
    derivation = gain_derivation(design, narrowest.margin, narrowest.time, a, spec.gain)
    gain_ok = derivation["gain"] < derivation["stable_gain_limit"]
    checks = [Check("sampled.gain", gain_ok, derivation["explanation"]
                    + ("" if gain_ok else f"; k = {derivation['gain']:.6g} is beyond the "
                       f"limit at g_max = {a.input_gain[1]:g}"), derivation)]
    result = check_sampled(design, samples, a)
    if result.passed:
        detail = (f"every plant with {_bounds_words(a)} stays strictly inside the tube at "
                  f"and between samples at {design.rate_hz:g} Hz with k = {design.gain:.6g}:"
                  f" |e| <= {result.level:.4g} at the samples, room >= {result.margin:.3g} "
                  f"of the half-width (least at t = {result.time:.4f} s, dimension "
                  f"{result.dimension})")
    else:
        rate, gain = lowest_rate(design, spec, a, spec.gain)
        g_max = a.input_gain[1]
        if rate is not None:
            need = f"the condition needs {rate / 1000:.3g} kHz (k = {gain:.4g}) at g_max = {g_max:g}"
        else:
            need = (f"no rate up to {design.rate_hz * RATE_FACTORS[-1] / 1000:g} kHz passes "
                    f"the condition at g_max = {g_max:g}")
            if a.input_gain_coupling > 0:
                need += (f" (row coupling {a.input_gain_coupling:g} next to g_min = "
                         f"{a.input_gain[0]:g}: declare a smaller input_gain_coupling if the "
                         "structure of g allows)")
        label = "controller.gain" if spec.gain is not None else "the derived gain"
        detail = (f"{result.reason}, for plants with {_bounds_words(a)} at "
                  f"{design.rate_hz:g} Hz and k = {design.gain:.6g} ({label}); {need}")
    checks.append(Check("sampled.tube_kept", result.passed, detail,
                        {**result.data, "level": result.level, "margin": result.margin,
                         "time": result.time}))
    return checks


def _drift_bound(plant: LinearPlant, space) -> float:
    """``max_{x in X} |a x + c|``: at a vertex of the box (the norm is convex); for more
    than 12 dimensions the bound ``|a m + c| + sum_j |a_j| r_j`` (centre m, half-widths r)."""
    a, c = np.array(plant.a), np.array(plant.c)
    lo, hi = np.array(space.lower), np.array(space.upper)
    if lo.size <= 12:
        corners = np.array(list(itertools.product(*zip(lo, hi))))
        return float(np.linalg.norm(corners @ a.T + c, axis=1).max())
    m, r = (lo + hi) / 2, (hi - lo) / 2
    return float(np.linalg.norm(a @ m + c) + np.linalg.norm(a, axis=0) @ r)


def linear_plant_checks(spec: Spec) -> list[Check]:
    """Assumption 2 for the spec's ``linear`` plant, and whether it meets ``[assumptions]``.

    Returns
    -------
    list of Check
        ``assumption2.linear`` (``lambda_min((g + g^T)/2) > 0``) and
        ``sampled.plant_within_assumptions`` (the plant's ``g``, skew part, row coupling
        and ``max |a x + c|`` over the state space against the declared bounds).
    """
    plant = spec.linear_plant
    n = spec.dimension
    if plant is None:
        eye = tuple(tuple(float(i == j) for j in range(n)) for i in range(n))
        plant = LinearPlant(tuple(tuple(0.0 for _ in range(n)) for _ in range(n)), eye,
                            tuple(0.0 for _ in range(n)))
    g = np.array(plant.g)
    sym, skew = (g + g.T) / 2, (g - g.T) / 2
    eig = np.linalg.eigvalsh(sym)
    checks = [Check("assumption2.linear", bool(eig[0] > 0),
                    f"lambda_min((g + g^T)/2) = {eig[0]:.6g} for the linear plant's g"
                    + ("" if eig[0] > 0 else ": Assumption 2 fails, law (13) cannot hold "
                       "this plant"), {"lambda_min": float(eig[0])})]
    off = g - np.diag(np.diag(g))
    found = {"input_gain": (float(eig[0]), float(eig[-1])),
             "input_gain_skew": float(np.linalg.norm(skew, 2)),
             "input_gain_coupling": float(np.linalg.norm(off, axis=1).max()),
             "drift_bound": _drift_bound(plant, spec.state_space)}
    a = spec.assumptions
    tol = 1e-12
    bad = []
    if found["input_gain"][0] < a.input_gain[0] - tol or found["input_gain"][1] > a.input_gain[1] + tol:
        bad.append(f"eig((g + g^T)/2) spans [{found['input_gain'][0]:.6g}, "
                   f"{found['input_gain'][1]:.6g}], outside input_gain {list(a.input_gain)}")
    for key in ("input_gain_skew", "input_gain_coupling", "drift_bound"):
        if found[key] > getattr(a, key) + tol:
            bad.append(f"{key} is {found[key]:.6g} > {getattr(a, key):g}")
    checks.append(Check("sampled.plant_within_assumptions", not bad,
                        "the linear plant meets [assumptions] (eig in "
                        f"[{found['input_gain'][0]:.6g}, {found['input_gain'][1]:.6g}], skew "
                        f"{found['input_gain_skew']:.3g}, coupling "
                        f"{found['input_gain_coupling']:.3g}, max |a x + c| "
                        f"{found['drift_bound']:.3g})" if not bad else "; ".join(bad),
                        {k: v for k, v in found.items()}))
    return checks
