"""Sampled-data certificate of the cascade: the held input keeps both tubes, per interval.

The deployed cascade (docs/second-order.md) reads ``x1(t_k)``, ``x2(t_k)``, computes
``u_k = -k2 xi2 epsilon2`` and holds it until ``t_{k+1} = t_k + h``. This module proves,
for every plant ``x1_dot = x2``, ``x2_dot = f + g u + w`` of a :class:`CascadeClass`
(``g`` symmetric with eigenvalues in ``[g_min, g_max]``, off-diagonal rows at most
``coupling``; ``|f_i| <= F0 + F1 |x2_i|``; ``|w_i| <= W``), that ``|e1| < 1`` and
``|e2| < 1`` at and between the samples over the horizon of the tube's samples. It
propagates, from ``(e1(0), e2(0))``, one interval per axis for each error at the samples
and, on each sampling interval, reuses the first-order per-axis enclosure
(:func:`~stt_codegen.design.certificate.sampled_axis.axis_interval`) twice:

* the **position stage** is law (13) with ``g = 1`` on ``x1_dot = x2 = r_k + d(t)``:
  ``d = z_k + (x2(t) - x2_k)`` displaces ``x1`` by at most ``tau (Z + h A / 2)`` after
  ``tau`` seconds (``|z_k| <= Z``, ``|x2_dot| <= A``);
* the **velocity stage** is law (13)'s transform on the tube ``|z| < rho2``, ``z = x2 -
  r``: ``z`` moves by ``tau g u_k`` plus the drift and disturbance (at most ``tau (F +
  W)``), the other axes' inputs through the coupling, and the change of ``r`` along the
  trajectory, bounded by :func:`virtual_velocity_change` (uniform on the interval).

With ``[controller] delay`` and ``jitter`` (``delay=``, ``jitter=``) the previous force
acts for the first ``lag`` of each measurement interval and the interval's length varies;
the check takes the corners of both, as the first order does (docs/second-order.md, "A
computation delay and jitter").

The argument, its assumptions and what it does not prove: docs/second-order.md, "The
sampled cascade (certificate)". Plain floats in the loop, like :mod:`.sampled`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from .cascade_bounds import STEP_PIECES, step_velocity_change, virtual_velocity_change
from .cascade_step import FIGURES, RHO_ROUNDING, predicted_step, sampled_step
from .enclosures import enclose_later
from .folded import run_steps
from .growing import GrowingEnclosure
from ..samples import TubeSamples, sample_tube
from ...progress import report
from ...spec.loader import Spec
from ...spec.plants import SECOND_ORDER_PLANTS
from ...spec.second_order import model_bounds
from ...spec.variants import require_variant
from ...tube import reference
from ...tube.parameters import E_MAX, GAMMA_D_MIN, TubeDesign
from ...tube.second_stage import SecondStage
from .sampled import DELAY_HALVINGS, largest_passing, worst_near
from .sampled_axis import peak, phi_scalar

__all__ = ["CascadeClass", "CascadeCheck", "RHO_ROUNDING", "STEP_PIECES", "cascade_check_of",
           "cascade_class", "model_within_class", "certify_stage", "check_cascade_predicted",
           "check_cascade_sampled", "largest_cascade_delay", "step_velocity_change",
           "tube_figures", "virtual_velocity_change"]

#: Progress events the per-sample loop of :func:`check_cascade_sampled` reports at most
#: (:mod:`stt_codegen.progress`; nothing without a receiver).
PROGRESS_REPORTS = 50


@dataclass(frozen=True)
class CascadeClass:
    """The second-order plants the certificate covers (docs/second-order.md).

    Attributes
    ----------
    g_min, g_max : float
        Range of the eigenvalues of the (symmetric) input matrix ``g``, ``0 < g_min <=
        g_max`` (input units to acceleration).
    coupling : float
        Bound of the Euclidean norm of the off-diagonal part of a row of ``g``; 0 for a
        model whose ``g`` is diagonal; at most ``(g_max - g_min) / 2`` for any symmetric
        ``g`` of the range.
    drift_bound : float or tuple of float
        ``F0``: ``|f_i| <= F0_i + F1 |x2_i|``, velocity units per second; one number for
        every axis, or one per axis (a quadrotor's gravity acts on its vertical axis only).
    drift_slope : float
        ``F1`` (e.g. damping over mass), 1/s; ``h F1 < 1`` is needed.
    disturbance_bound : float
        ``W >= |w_i|``, velocity units per second.
    velocity_bound : tuple of float or None
        ``state_space.velocity_bound``: the certificate also proves ``|x2_i|`` below it
        (the drift bound is declared over those velocities).
    """

    g_min: float
    g_max: float
    coupling: float
    drift_bound: float | tuple[float, ...]
    drift_slope: float = 0.0
    disturbance_bound: float = 0.0
    velocity_bound: tuple[float, ...] | None = None

    def drift_bounds(self, n: int) -> np.ndarray:
        """``F0_i`` of each of ``n`` axes, shape ``(n,)``.

        Raises
        ------
        ValueError
            ``drift_bound`` has neither one entry nor ``n``.
        """
        f0 = np.asarray(self.drift_bound, dtype=float).reshape(-1)
        if f0.size not in (1, n):
            raise ValueError(f"drift_bound needs 1 or {n} entries, got {f0.size}")
        return np.broadcast_to(f0, (n,)).copy()

    def words(self) -> str:
        """The class in one phrase (for reports)."""
        f0 = np.asarray(self.drift_bound, dtype=float).reshape(-1)
        drift = (f"|f_i| <= {f0[0]:.6g}" if f0.size == 1 else
                 "|f_i| <= [" + ", ".join(f"{v:.6g}" for v in f0) + "]_i")
        if self.drift_slope:
            drift += f" + {self.drift_slope:.6g} |x2_i|"
        coupling = ("g diagonal" if self.coupling == 0.0 else
                    f"off-diagonal rows of g <= {self.coupling:.6g}")
        return (f"g symmetric with eigenvalues in [{self.g_min:.6g}, {self.g_max:.6g}] "
                f"({coupling}), {drift}, |w_i| <= {self.disturbance_bound:.3g}")


def _one_or_per_axis(bounds: tuple[float, ...]) -> float | tuple[float, ...]:
    """``bounds`` as :attr:`CascadeClass.drift_bound` holds it: one number when every axis
    has the same, else one per axis."""
    return bounds if min(bounds) < max(bounds) else max(bounds)


def cascade_class(spec: Spec) -> CascadeClass:
    """The class of a spec with a second-order ``plant.model``: ``assumptions.input_gain``,
    ``assumptions.drift_bound`` (per axis where the spec or the model gives one per axis;
    ``F1 = 0``: a velocity-dependent drift is declared at
    ``state_space.velocity_bound``, which the certificate proves is kept),
    ``plant.disturbance_amplitude``; coupling 0 for a model with a diagonal ``g``
    (:attr:`~stt_codegen.spec.plants.SecondOrderModel.diagonal_input`), else ``(g_max -
    g_min) / 2``.

    Parameters
    ----------
    spec : Spec
        With a second-order ``plant.model``.

    Returns
    -------
    CascadeClass

    Raises
    ------
    SpecError
        The spec is not of the cascade variant (field ``plant.model``; a ``ValueError``).
    """
    require_variant(spec, "cascade", "cascade_class")
    order = spec.second_order
    g_min, g_max = order.input_gain
    diagonal = SECOND_ORDER_PLANTS[order.model].diagonal_input
    return CascadeClass(g_min, g_max, 0.0 if diagonal else 0.5 * (g_max - g_min),
                        _one_or_per_axis(order.drift_bounds), 0.0,
                        spec.disturbance_amplitude,
                        order.velocity_bound)


@dataclass(frozen=True)
class CascadeCheck:
    """Outcome of :func:`check_cascade_sampled`.

    Attributes
    ----------
    passed : bool
        The sufficient condition holds on every interval of the samples.
    reason : str
        Empty when passed, else what fails, in numbers.
    position_margin : float
        Least room between the enclosure of ``x1`` and the tube's edge, over the tube's
        half-width (negative when failed there).
    velocity_margin : float
        Least ``1 - max |e2|`` between samples.
    max_abs_e1, max_abs_e2 : float
        The proved bounds of ``|e1|``, ``|e2|`` at the samples.
    peak_input : tuple of float
        Per axis, the proved bound of ``|u_k,i|`` over the samples (input units), hence of
        the held input at every instant of the horizon.
    peak_input_time : tuple of float
        Per axis, the sample instant where that bound is reached, seconds.
    peak_velocity : tuple of float
        Per axis, the proved bound of ``|x2_i|`` on the intervals.
    time : float
        Start of the interval where the smaller margin is least (or of the failure), s.
    dimension : int
        Its axis.
    data : dict
        JSON-ready figures.
    """

    passed: bool
    reason: str
    position_margin: float
    velocity_margin: float
    max_abs_e1: float
    max_abs_e2: float
    peak_input: tuple[float, ...]
    peak_velocity: tuple[float, ...]
    time: float
    dimension: int
    data: dict = field(default_factory=dict)
    peak_input_time: tuple[float, ...] = ()


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

    def absorb(self, figures: np.ndarray, times: np.ndarray,
               failure: tuple[int, str, int] | None) -> None:
        """Take the figures of the steps run (``(8, n, K)``,
        :data:`~.cascade_step.FIGURES`) up to the judgement that failed (``(k, what, i)``
        of :func:`_first_failure`, or ``None``), as the per-sample loop takes them: at a
        sample the bounds of ``|e1|`` and ``|e2|``; then, axis by axis, the input and the
        velocity, the position room, the velocity room (the least room of both and where,
        first reached, only when nothing failed)."""
        f = dict(zip(FIGURES, figures))
        n, count = figures.shape[1], figures.shape[2]
        steps = min(count, failure[0] + 1) if failure else count
        done = np.zeros((n, count), dtype=bool)       # the axes judged before the failure
        done[:, :steps] = True
        reached = [True, True, True]                  # input and speed, room, vroom
        axis = None                                   # the axis judged when it failed
        if failure:
            k, what, i = failure
            if what in ("e1", "e2"):
                done[:, k] = False
            else:
                done[i:, k] = False
                axis = i
                reached = [True, what not in ("input", "speed"), what in ("vroom", "reach")]
        for name, place in (("reach1", 0), ("reach2", 1)):
            self.top[place] = max(self.top[place], float(f[name][:, :steps].max()))

        def taken(name: str, i: int, also: bool) -> tuple[np.ndarray, np.ndarray]:
            mask = done[i].copy()
            if i == axis:
                mask[failure[0]] = also
            return f[name][i][mask], np.flatnonzero(mask)

        for i in range(n):
            u, at = taken("u_abs", i, reached[0])
            if u.size and u.max() > self.peak_u[i]:
                j = int(np.argmax(u))                 # the first sample reaching it
                self.peak_u[i], self.peak_t[i] = float(u[j]), float(times[at[j]])
            speed, _ = taken("speed", i, reached[0])
            if speed.size:
                self.peak_x2[i] = max(self.peak_x2[i], float(speed.max()))
        worst = self.worst
        for key, name, also in (("position", "room", reached[1]),
                                ("velocity", "vroom", reached[2])):
            values = np.concatenate([taken(name, i, also)[0] for i in range(n)])
            if values.size:
                worst[key] = min(worst[key], float(values.min()))
        if failure is None and count:
            least = np.minimum(f["room"], f["vroom"]).T.ravel()      # (k, i) in order
            j = int(np.argmin(least))
            if least[j] < worst["least"]:
                worst.update(least=float(least[j]), t=float(times[j // n]), i=j % n)

    def close(self, state: np.ndarray, n: int) -> None:
        """Take the bounds of ``|e1|``, ``|e2|`` at the last sample (``state``: the boxes of
        ``e1`` and ``e2``, lower bounds then upper)."""
        box = state[:4 * n].reshape(4, n)
        self.top[0] = max(self.top[0], max(max(-a, b) for a, b in zip(box[0].tolist(),
                                                                      box[1].tolist())))
        self.top[1] = max(self.top[1], max(max(-a, b) for a, b in zip(box[2].tolist(),
                                                                      box[3].tolist())))

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


# The tube's enclosures (of every interval, and of the actuation intervals with a delay)
# are computed with numpy's kernels whatever context calls the check, as every other
# certificate's (reference.numpy_math): one check gives the same floats from the design,
# verify and the tests.
@reference.numpy_math()
def check_cascade_sampled(design: TubeDesign, samples: TubeSamples, stage: SecondStage,
                          plants: CascadeClass, initial_velocity, *, delay: float = 0.0,
                          jitter: float = 0.0, compensate: bool = False,
                          enclosure: GrowingEnclosure | None = None,
                          input_limit: tuple[float, ...] | None = None) -> CascadeCheck:
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
    enclosure : GrowingEnclosure, optional
        The enclosure of ``design``'s ``samples``, when the caller keeps it (it depends on
        the tube only, not on the stage: :func:`tube_figures`); a new one when ``None``.
    input_limit : tuple of float, optional
        Per axis, a bound of ``|u_k,i|`` at which the check stops and fails (reason
        ``|u_i| may reach ...``): for a search that only asks whether the stage keeps both
        tubes within an input bound (:func:`~..cascade_gain.certified_stage` without
        advice). Up to that sample the figures are the full check's; a check that never
        reaches it is the full check.

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
                                       delay=delay, enclosure=enclosure,
                                       input_limit=input_limit)
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
    f0, f1, w_amp = plants.drift_bounds(n), plants.drift_slope, plants.disturbance_bound
    vbound = plants.velocity_bound
    tally = _Tally(design, stage, plants, {"delay": delay, "jitter": jitter} if timed else {})
    refused = _unfit(stage, samples, plants, longest if timed else h)
    if refused:
        return tally.result(False, refused)
    lo, hi = samples.gamma_lower, samples.gamma_upper
    growing = GrowingEnclosure(design, samples) if enclosure is None else enclosure
    count = growing.count
    half, centre = 0.5 * (hi - lo), 0.5 * (hi + lo)
    rho2_all = _rho2(stage, samples.t)
    if timed:
        shares1 = sorted({length / h for length in lengths})
        spans = sorted(set(lengths))
    else:
        shares1, corners, spans = [1.0], [(1.0, 0.0)], [h]

    def column(a: int, b: int) -> dict:
        """The tube's figures of intervals ``a .. b - 1`` (:data:`.cascade_step.SAMPLED_COLUMNS`),
        each ``(b - a, n)`` or ``(b - a, copies n)``."""
        # with jitter an interval reaches into its neighbours: the tube's enclosure is the
        # worst of intervals k - 1 .. k + 1, in absolute units (then in interval k's
        # coordinates); each row depends on its interval alone, so these are the rows of
        # the whole tube's
        enc = growing.first(b + 1)
        upper_min, lower_max = (worst_near(enc.upper_min, jitter, np.minimum)[a:b],
                                worst_near(enc.lower_max, jitter, np.maximum)[a:b])
        upper_max, lower_min = (worst_near(enc.upper_max, jitter, np.maximum)[a:b],
                                worst_near(enc.lower_min, jitter, np.minimum)[a:b])
        width = hi[a:b] - lo[a:b]
        rho = rho2_all[a:b]
        # the velocity stage's pull and peak on every interval at once (one bisection over
        # the array, the same floats as one interval at a time)
        pull2_all = 2.0 * h * k2 / rho
        out = {"centre": centre[a:b], "half": half[a:b],
               "centre_next": centre[a + 1:b + 1], "half_next": half[a + 1:b + 1],
               "pull1": 4.0 * h * k1 / width,
               "up_e": (upper_min - centre[a:b]) / half[a:b],
               "low_e": (lower_max - centre[a:b]) / half[a:b],
               "room_up": upper_min, "room_low": lower_max,
               "width_min": worst_near(enc.width_min, jitter, np.minimum)[a:b],
               "width_max": upper_max - lower_min,
               "move": (lower_max - lower_min) + (upper_max - upper_min),
               "rho": rho, "rho_next": rho2_all[a + 1:b + 1]}
        if timed:
            # s* of each share of a period the own force (the virtual velocity) acts
            out["peak1"] = np.hstack([peak(0.5 * width / (share * 4.0 * h * k1 / width))
                                      for share in shares1])
            out["peak2"] = np.hstack([peak(rho / (g_min * share * pull2_all))
                                      if share > 0.0 else np.full((b - a, n), 1.0 - 1e-15)
                                      for share, _ in corners])
            # rho2 decreases: its least on a measurement interval is at t_{k+1} + jitter
            out["edge"] = _rho2(stage, samples.t[a + 1:b + 1] + jitter)
        else:
            out["peak1"] = peak(0.5 * width / (4.0 * h * k1 / width))
            out["peak2"] = peak(rho / (g_min * pull2_all))
            out["edge"] = out["rho_next"]
        return out

    step, columns, constants = sampled_step(n, timed, delay > 0.0, len(shares1), len(corners),
                                            len(spans))
    x1_0 = np.array(design.initial_state, dtype=float)
    e1_0 = ((x1_0 - centre[0]) / half[0]).tolist()
    r0 = [-(4.0 * k1 / (2.0 * float(half[0][i]))) * phi_scalar(e1_0[i]) for i in range(n)]
    x2_0 = [float(v) for v in initial_velocity]
    e2_0 = [(x2_0[i] - r0[i]) / float(rho2_all[0][i]) for i in range(n)]
    start = np.array(e1_0 + e1_0 + e2_0 + e2_0 + [0.0] * n)   # no force before the first
    fixed = constants.pack({
        "k1": k1, "k2": k2, "h": h, "g_min": g_min, "g_max": g_max, "coupling": cpl,
        "f0": f0, "f1": f1, "w": w_amp, "longest": longest, "delay": delay,
        "vbound": np.inf if vbound is None else vbound, "share": shares1,
        "corner_share": [share for share, _ in corners],
        "corner_lag": [lag for _, lag in corners], "length": spans})
    figures, state = _run(step, start, lambda a, b: columns.pack(
        {name: value.T for name, value in column(a, b).items()}, b - a), count, fixed,
        lambda r: r <= E_MAX, vbound, input_limit, samples, "the sampled cascade's")
    failure = _first_failure(figures, lambda r: r <= E_MAX, vbound, input_limit)
    tally.absorb(figures, samples.t, failure)
    if failure is not None:
        k, what, i = failure
        t, f = float(samples.t[k]), {name: float(v[i, k]) for name, v in zip(FIGURES, figures)}
        span = f"[{t:.4f}, {t + h:.4f}] s"
        if what in ("e1", "e2"):
            reach = f["reach1" if what == "e1" else "reach2"]
            reason = (f"|{what}_{i}| may reach {reach:.6g} at t = {t:.4f} s, beyond the clamp "
                      "E_MAX")
        else:
            edge = float(column(k, k + 1)["edge"][0][i]) * (1.0 - RHO_ROUNDING)
            reason = _axis_reason(what, i, f, span, vbound, f["dr"] / edge,
                                  f"|e1_{i}| may reach {f['reach_next']:.6g} at t = "
                                  f"{t + h:.4f} s", input_limit)
        return tally.result(False, reason, t, i)
    tally.close(state, n)
    tally.data["horizon"] = float(samples.t[count])
    return tally.result(True, "")


def _first_failure(figures: np.ndarray, inside, vbound,
                   limit=None) -> tuple[int, str, int] | None:
    """Where the per-sample loop first fails in ``figures`` (``(8, n, K)``,
    :data:`~.cascade_step.FIGURES`), in the order it judges: at a sample the bounds of
    ``|e1|`` then ``|e2|`` (``inside``: what they must satisfy), then axis by axis the
    input (above ``limit``, when given), the velocity bound, the position room, the
    velocity room, the next ``|e1|``. A figure that is not a number fails. ``(k, what, i)``
    or ``None``."""
    f = dict(zip(FIGURES, figures))
    e1 = ~inside(f["reach1"].max(axis=0))
    e2 = ~inside(f["reach2"].max(axis=0))
    over = (np.zeros(f["u_abs"].shape, dtype=bool) if limit is None
            else f["u_abs"] > np.array(limit, dtype=float)[:, None])
    fast = (np.isnan(f["speed"]) if vbound is None
            else ~(f["speed"] < np.array(vbound, dtype=float)[:, None]))
    per_axis = np.stack([over, fast, ~(f["room"] > 0.0), ~(f["vroom"] > 0.0),
                         ~(f["reach_next"] < 1.0)])
    bad = e1 | e2 | per_axis.any(axis=(0, 1))
    if not bad.any():
        return None
    k = int(np.argmax(bad))
    if e1[k] or e2[k]:
        name = "reach1" if e1[k] else "reach2"
        return k, "e1" if e1[k] else "e2", int(np.argmax(f[name][:, k]))
    i = int(np.argmax(per_axis[:, :, k].any(axis=0)))
    return k, _STAGES[int(np.argmax(per_axis[:, i, k]))], i


#: The judgements of one axis on one interval, in the loop's order.
_STAGES = ("input", "speed", "room", "vroom", "reach")


def _run(step, start, columns, count: int, constants, inside, vbound, limit,
         samples: TubeSamples, whose: str):
    """:func:`~.folded.run_steps` until the first failure, reporting progress."""
    end = float(samples.t[-1])

    def progress(done: int) -> None:
        report("cascade certificate", done / count, f"{whose} certificate: t = "
               f"{float(samples.t[done]):.3g} s of {end:.3g} s")

    return run_steps(step, start, columns, count, constants,
                     lambda figures: _first_failure(figures, inside, vbound,
                                                    limit) is not None,
                     progress)


def _axis_reason(what: str, i: int, f: dict, span: str, vbound, change: float,
                 next_words: str, limit=None) -> str:
    """The words of a failure on one axis (``f``: its figures at the failing step)."""
    if what == "input":
        return (f"|u_{i}| may reach {f['u_abs']:.4g} on {span}, beyond the input bound "
                f"{limit[i]:g} (the check stops there)")
    if what == "speed":
        return (f"|x2_{i}| may reach {f['speed']:.4g} on {span}"
                + ("" if vbound is None else f", beyond velocity_bound {vbound[i]:g} (the "
                   "drift bound is declared within it)"))
    if what == "room":
        return (f"the position may leave its tube in dimension {i} on {span} (the enclosure "
                f"of x1 reaches {-f['room']:.3g} half-widths beyond its edge)")
    if what == "vroom":
        return (f"the velocity error may leave its tube in dimension {i} on {span} (|e2| up "
                f"to {1.0 - f['vroom']:.4g}; the change of r alone is {change:.3g} of rho2)")
    return next_words


# numpy's kernels for the tube's enclosures, as check_cascade_sampled
@reference.numpy_math()
def check_cascade_predicted(design: TubeDesign, samples: TubeSamples, stage: SecondStage,
                            plants: CascadeClass, initial_velocity, *, delay: float,
                            enclosure: GrowingEnclosure | None = None,
                            input_limit: tuple[float, ...] | None = None) -> CascadeCheck:
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
    enclosure : GrowingEnclosure, optional
        The enclosure of ``design``'s ``samples`` (:func:`tube_figures`); a new one when
        ``None``.
    input_limit : tuple of float, optional
        As in :func:`check_cascade_sampled`.

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
    f0, f1, w_amp = plants.drift_bounds(n), plants.drift_slope, plants.disturbance_bound
    deviation = 0.5 * (g_max - g_min)                     # |g_ii - g_mid|
    g_mid = 0.5 * (g_max + g_min)
    share = 1.0 - min(delay / h, 1.0)          # of a period x_hat's step is uncertain
    mix_lo = share * g_min + (1.0 - share) * g_mid
    mix_hi = share * g_max + (1.0 - share) * g_mid
    vbound = plants.velocity_bound
    tally = _Tally(design, stage, plants, {"delay": delay, "jitter": 0.0,
                                           "compensate_delay": True})
    result, judged = tally.result, tally.judged
    refused = _unfit(stage, samples, plants, h)
    if refused:
        return result(False, refused)
    lo, hi = samples.gamma_lower, samples.gamma_upper
    enc = (GrowingEnclosure(design, samples) if enclosure is None else enclosure).first(
        len(samples.t) - 1)
    count = len(enc.t_start)
    half, centre = 0.5 * (hi - lo), 0.5 * (hi + lo)
    rho2 = _rho2(stage, samples.t)
    pull2_all = 2.0 * h * k2 / rho2[:count]
    # over the actuation interval [t_k + delay, t_{k+1} + delay] (absolute units)
    act = enclose_later(design, samples, delay, delay)
    # r changes from (x1_hat_k, t_k) to (x1(t), t), t <= t_{k+1} + delay: the tube's span
    # and widths over [t_k, t_{k+1} + delay]
    whole = enclose_later(design, samples, 0.0, delay)
    column = {"centre": centre[:count], "half": half[:count],
              "centre_next": centre[1:count + 1], "half_next": half[1:count + 1],
              "pull1": (4.0 * h * k1 / (hi - lo))[:count],
              "peak1": peak(0.5 * (hi - lo) / (4.0 * h * k1 / (hi - lo)))[:count],
              "up_e": (act.upper_min - centre[:count]) / half[:count],
              "low_e": (act.lower_max - centre[:count]) / half[:count],
              "room_up": act.upper_min, "room_low": act.lower_max,
              "width_max_a": act.upper_max - act.lower_min,
              "move_r": (whole.lower_max - whole.lower_min) + (whole.upper_max
                                                               - whole.upper_min),
              "width_min_r": whole.width_min, "width_max_r": whole.upper_max - whole.lower_min,
              "move": (enc.lower_max - enc.lower_min) + (enc.upper_max - enc.upper_min),
              "width_min": enc.width_min, "width_max": enc.upper_max - enc.lower_min,
              "rho": rho2[:count], "rho_next": rho2[1:count + 1],
              "peak2": peak(rho2[:count] / (g_min * pull2_all)),
              # rho2 decreases: its least on [a_k, a_{k+1}] is at t_{k+1} + delay
              "late": _rho2(stage, samples.t[1:count + 1] + delay)}
    first = {name: value[0].tolist() for name, value in column.items()}

    def r_of(e1: float, i: int) -> float:
        return -(4.0 * k1 / (2.0 * first["half"][i])) * phi_scalar(e1)

    # (C0) before the first force acts: [0, delay], no force
    x1_0 = [float(v) for v in design.initial_state]
    x2_0 = [float(v) for v in initial_velocity]
    edge0 = _rho2(stage, np.array([delay]))[0].tolist()
    box1, box2, eta1, eta2 = [], [], [], []
    for i in range(n):
        speed = (abs(x2_0[i]) + delay * (f0[i] + w_amp)) / (1.0 - delay * f1)
        tally.peak_x2[i] = speed
        if vbound is not None and speed >= vbound[i]:
            return result(False, f"|x2_{i}| may reach {speed:.4g} on [0, {delay:.4g}] s, "
                          f"beyond velocity_bound {vbound[i]:g}", 0.0, i)
        accel = f0[i] + f1 * speed + w_amp
        p_lo, p_hi = x1_0[i] - delay * speed, x1_0[i] + delay * speed
        e1_0 = (x1_0[i] - first["centre"][i]) / first["half"][i]
        room = min(float(enc.upper_min[0][i]) - p_hi,
                   p_lo - float(enc.lower_max[0][i])) / first["half"][i]
        if room <= 0.0 or abs(e1_0) >= 1.0:
            return result(False, f"the position may leave its tube in dimension {i} on "
                          f"[0, {delay:.4g}] s, before the first force acts", 0.0, i)
        gap = room * first["half"][i]
        dr = virtual_velocity_change(k1, 1.0, abs(e1_0),
                                     max(1.0 - 2.0 * gap / first["width_max"][i], abs(e1_0)),
                                     delay * speed, first["move"][i], first["width_min"][i],
                                     first["width_max"][i])
        z_0 = x2_0[i] - r_of(e1_0, i)
        vroom = 1.0 - (abs(z_0) + delay * accel + dr) / (edge0[i] * (1.0 - RHO_ROUNDING))
        judged(room, vroom, 0.0, i)
        if vroom <= 0.0:
            return result(False, f"the velocity error may leave its tube in dimension {i} "
                          f"on [0, {delay:.4g}] s, before the first force acts", 0.0, i)
        # the prediction at s_0 = 0 (u_{-1} = 0) and its miss (C1)
        e1_hat = (x1_0[i] + delay * x2_0[i] - first["centre"][i]) / first["half"][i]
        if abs(e1_hat) >= 1.0:
            return result(False, f"the predicted position leaves its tube in dimension {i} "
                          "at t = 0", 0.0, i)
        e2_hat = (x2_0[i] - r_of(e1_hat, i)) / first["rho"][i]
        box1.append(e1_hat)
        box2.append(e2_hat)
        eta2.append(delay * accel)
        eta1.append(0.5 * delay * delay * accel)
    step, columns, constants = predicted_step(n)
    fixed = constants.pack({
        "k1": k1, "k2": k2, "h": h, "g_min": g_min, "g_max": g_max, "coupling": cpl,
        "f0": f0, "f1": f1, "w": w_amp, "delay": delay, "deviation": deviation,
        "g_mid": g_mid, "share": share, "mix_lo": mix_lo, "mix_hi": mix_hi,
        "vbound": np.inf if vbound is None else vbound})
    start = np.array(box1 + box1 + box2 + box2 + eta1 + eta2)
    figures, state = _run(step, start, lambda a, b: columns.pack(
        {name: value[a:b].T for name, value in column.items()}, b - a), count, fixed,
        lambda r: r < 1.0, vbound, input_limit, samples, "the predicted cascade's")
    failure = _first_failure(figures, lambda r: r < 1.0, vbound, input_limit)
    tally.absorb(figures, samples.t, failure)
    if failure is not None:
        k, what, i = failure
        t, f = float(samples.t[k]), {name: float(v[i, k]) for name, v in zip(FIGURES, figures)}
        if what in ("e1", "e2"):
            reach = f["reach1" if what == "e1" else "reach2"]
            reason = (f"|{what}_{i}| of the predicted state may reach {reach:.6g} at t = "
                      f"{t:.4f} s (the check needs it inside its tube)")
        else:
            reason = _axis_reason(what, i, f, f"[{t + delay:.4f}, {t + h + delay:.4f}] s",
                                  vbound, f["dr"] / float(column["late"][k][i]),
                                  f"|e1_{i}| of the predicted state may reach "
                                  f"{f['reach_next']:.6g} at t = {t + h:.4f} s (the check "
                                  "needs it inside its tube)", input_limit)
        return result(False, reason, t, i)
    tally.close(state, n)
    tally.data["horizon"] = float(samples.t[count])
    return result(True, "")


def certify_stage(tube: TubeDesign, spec: Spec, stage: SecondStage,
                  input_limit: tuple[float, ...] | None = None) -> tuple[bool, dict]:
    """:func:`check_cascade_sampled` for ``spec``'s declared plants (:func:`cascade_class`)
    and its ``[controller] delay`` and ``jitter`` on ``tube`` sampled at its rate: the
    design's certifier
    (:func:`~stt_codegen.design.cascade_gain.certified_stage` asks it).

    Parameters
    ----------
    tube : TubeDesign
        The position tube.
    spec : Spec
        With a second-order ``plant.model``.
    stage : SecondStage
        The second stage to certify.
    input_limit : tuple of float, optional
        Stop and fail where ``|u_i|`` passes it (:func:`check_cascade_sampled`).

    Returns
    -------
    passed : bool
    report : dict
        :attr:`CascadeCheck.data` with ``passed``, ``reason``, ``time``, ``dimension``.
    """
    check = cascade_check_of(tube, spec, stage, input_limit)
    return check.passed, {**check.data, "passed": check.passed, "reason": check.reason,
                          "time": check.time, "dimension": check.dimension}


@lru_cache(maxsize=64)
def cascade_check_of(tube: TubeDesign, spec: Spec, stage: SecondStage,
                     input_limit: tuple[float, ...] | None = None) -> CascadeCheck:
    """:func:`check_cascade_sampled` of ``stage`` on ``tube`` for ``spec``'s declared
    plants and its ``[controller] delay`` and ``jitter``, once per process (the design,
    ``verify`` and the rate search ask again).

    Parameters
    ----------
    tube : TubeDesign
        The position tube, sampled at its rate.
    spec : Spec
        With a second-order ``plant.model``; its ``delay + 2 jitter`` must fit the period
        of ``tube.rate_hz``.
    stage : SecondStage
        The second stage to certify.
    input_limit : tuple of float, optional
        Stop and fail where ``|u_i|`` passes it (:func:`check_cascade_sampled`); a check
        with a limit is kept apart from the full one.

    Returns
    -------
    CascadeCheck
    """
    samples, enclosure = tube_figures(tube)
    return check_cascade_sampled(tube, samples, stage, cascade_class(spec),
                                 spec.second_order.initial_velocity, delay=spec.delay,
                                 jitter=spec.jitter, compensate=spec.compensate_delay,
                                 enclosure=enclosure, input_limit=input_limit)


@lru_cache(maxsize=8)
def tube_figures(tube: TubeDesign) -> tuple[TubeSamples, GrowingEnclosure]:
    """The deployed samples of ``tube`` at its rate and their enclosure, once per tube:
    every second stage tried on a tube (the shapes, the delays) is checked on the same
    ones, and the enclosure's rows are computed as far as a check reaches.

    Parameters
    ----------
    tube : TubeDesign

    Returns
    -------
    samples : TubeSamples
    enclosure : GrowingEnclosure
    """
    with reference.numpy_math():
        samples = sample_tube(tube)
    return samples, GrowingEnclosure(tube, samples)


def largest_cascade_delay(tube: TubeDesign, spec: Spec, stage: SecondStage,
                          halvings: int = DELAY_HALVINGS) -> float | None:
    """The largest computation delay with which :func:`check_cascade_sampled` proves
    ``stage`` on ``tube`` at its rate with the spec's jitter, to ``h / 2^halvings`` below
    the true limit of the check (bisection; docs/second-order.md, "A computation delay
    and jitter").

    Parameters
    ----------
    tube : TubeDesign
        The position tube (its rate).
    spec : Spec
        With a second-order ``plant.model``: its declared plants and ``[controller]
        jitter``.
    stage : SecondStage
        The second stage judged.
    halvings : int, optional
        Halvings of the bisection on ``[0, h - 2 jitter]``; default
        :data:`~.sampled.DELAY_HALVINGS`, as the first order.

    Returns
    -------
    float or None
        Seconds, in ``[0, h - 2 jitter]``: the largest delay tried with which the check
        passes (a check with a delay proves every delay up to it); ``None`` when the check
        fails without delay.
    """
    samples, enclosure = tube_figures(tube)
    plants, start = cascade_class(spec), spec.second_order.initial_velocity

    def passes(delay: float) -> bool:
        return check_cascade_sampled(tube, samples, stage, plants, start, delay=delay,
                                     jitter=spec.jitter, compensate=spec.compensate_delay,
                                     enclosure=enclosure).passed

    # without delay: the spec's own check when it has no delay either (cached)
    return largest_passing(passes, max(0.0, 1.0 / tube.rate_hz - 2.0 * spec.jitter),
                           cascade_check_of(tube, spec, stage).passed if spec.delay == 0.0
                           else None, halvings)


def model_within_class(spec: Spec) -> tuple[bool, str, dict]:
    """Whether the spec's own simulated plant (``plant.model`` with ``plant.parameters``)
    belongs to its :func:`cascade_class`, so that the certificate covers it.

    The model's own bounds over the state space are
    :func:`~stt_codegen.spec.second_order.model_bounds`'s. ``double-integrator``: ``g = I /
    m``, ``f = 0``. ``quadrotor``: ``g = I / m``, ``f = -(c / m) x2 - g0 e3``, so ``|f_i| <=
    (c / m) |x2_i| + g0 [i = 3]``: within the drift bound where ``|x2_i| <
    velocity_bound_i`` (which the certificate proves); without a velocity bound only when
    ``c = 0``. ``two-link-arm``: the eigenvalues of ``M(q)^-1`` over the joint ranges and
    its Coriolis and gravity terms within ``velocity_bound``.

    Parameters
    ----------
    spec : Spec
        With a second-order ``plant.model``.

    Returns
    -------
    ok : bool
    words : str
    data : dict
    """
    order = spec.second_order
    cls = cascade_class(spec)
    own = model_bounds(order.model, order.parameters, spec.dimension, cls.velocity_bound,
                       spec.state_space.lower, spec.state_space.upper)
    if own is None:
        return False, (f"the {order.model} model has no equations: the certificate covers "
                       "the declared class only, not this plant"), {}
    g_min, g_max = own.input_gain
    n = spec.dimension
    drift = (np.full(n, math.inf) if own.drift_bounds is None else
             np.asarray(own.drift_bounds, dtype=float))
    declared = cls.drift_bounds(n)
    bad = []
    if not cls.g_min <= g_min <= g_max <= cls.g_max:
        bad.append(f"g in [{g_min:.6g}, {g_max:.6g}] outside input_gain [{cls.g_min:g}, "
                   f"{cls.g_max:g}]")
    for i in np.flatnonzero(drift > declared * (1 + 1e-12)):
        bad.append(f"max |f_{i}| = {drift[i]:.6g} (within velocity_bound) exceeds "
                   f"drift_bound {declared[i]:g}")
    data = {"input_gain": [g_min, g_max], "drift": drift.tolist()}
    drift = float(drift.max())
    if bad:
        return False, (f"the spec's {order.model} plant is outside the class the certificate "
                       "covers: " + "; ".join(bad)), data
    return True, (f"the spec's {order.model} plant ({own.words}; max |f_i| <= {drift:.6g} "
                  "within velocity_bound) is in the declared class"), data
